//! Per-element table for the dynamic solver: preload map joined with the calibration table.
