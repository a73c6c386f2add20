//! Pressure-measurement film: colour to pressure, smooth polynomial fit, preload per node.
