//! Pressure sweeps of the normal contact solver (placeholder).
