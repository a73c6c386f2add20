//! Pressure-measurement film: colour to pressure, smooth polynomial fit, preload per node.
//!
//! * [`colour`]: colour table / density calibration → per-pixel pressure or range class.
//! * [`regions`]: the image as a [`regions::FilmMap`], regions of interest, automatic patch
//!   detection, per-region summaries.
//! * [`polyfit`]: 2-D polynomial least-squares fit with R².
//! * [`nodes`]: contact nodes, placement on the film, tributary areas, preloads `N0 = σ·A`.
//! * [`reduce`]: node reduction on a coarse triangular mesh (area and load preserved).

pub mod colour;
pub mod nodes;
pub mod polyfit;
pub mod reduce;
pub mod regions;
