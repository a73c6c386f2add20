//! Calibration of element parameters (kn, E0, k, Et versus pressure) from BEM hysteresis loops.
