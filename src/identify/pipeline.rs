//! `asperity identify` as a library call: read levels, fit on some, select effects on held-out
//! rows, refit, score every level, estimate backbones, state the accelerance at given response
//! amplitudes, and write the files.
//!
//! Levels are numbered by increasing mean measured force (1 = lowest). By default the model is
//! fitted on the lowest and the highest level and scored on the others (which it predicts).

use super::backbone::{self, BackbonePoint, LevelBackbone};
use super::fit::{FitOptions, FitResult, LevelData};
use super::measured::{PhaseConvention, Quantity, Sweep};
use super::model::{Family, Model, ModelSpec, Scales};
use super::model_free::{self, ModelFreeCheck};
use super::report::{
    errors_table, fine_curve, level_role, level_roles, plot_backbone, plot_level, regions_text,
    write_json, write_rows_csv, CurveRow, InputFile, LevelErrors,
};
use super::select::{self, refit_all_rows, Round, SelectOptions, Selection, Verdict};
use super::stationarity::{self, SideComparison};
use super::uncertainty::{self, Ensemble, Uncertainty};
use crate::core::error::{Error, Result};
use crate::core::output::{write_atomic, write_string_atomic};
use realfft::num_complex::Complex64;
use serde::{Deserialize, Serialize};
use std::f64::consts::TAU;
use std::path::{Path, PathBuf};

/// Options of an identification.
#[derive(Debug, Clone, Serialize)]
pub struct Options {
    /// Constitutive law of the joint element the baseline is built on (Jenkins, Valanis, Iwan).
    pub family: Family,
    /// 1-based level numbers (by increasing mean force) to fit on; `None`: lowest and highest.
    pub fit_levels: Option<Vec<usize>>,
    /// Candidate effects and fit settings of the held-out effect search ([`select::select`]).
    pub select: SelectOptions,
    /// Nelder–Mead settings of the final refits on all rows of the fit levels.
    pub final_fit: FitOptions,
    /// Response amplitudes (unit of the lowest level's quantity) at which the identified
    /// model's response-controlled FRF is reported; `None`: the measured peak responses.
    pub response_amplitudes: Option<Vec<f64>>,
    /// Steps of each Metropolis chain of the prediction bands (0: no bands).
    pub chain_steps: usize,
    /// Rows of the fit levels the model is fitted to.
    pub rows: FitRows,
}

/// Rows of the fit levels the model is fitted to.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum FitRows {
    /// Every row.
    All,
    /// On a fit level whose two sides differ ([`stationarity::compare_sides`]: the structure
    /// changed while it was measured), only the resonance row and the rows after it — the part
    /// of the test after the structure has been through the level's largest amplitude; every
    /// row of the other levels.
    Settled,
}

/// Relative Nelder–Mead tolerance of the default (fast) search's baseline and candidate fits:
/// the held-out `ΔBIC` that decides between candidates needs each training cost to about
/// `1/n_eff` of itself (a few per cent), far coarser than the thorough search's
/// [`super::fit::THOROUGH_TOLERANCE`].
pub const FAST_TOLERANCE: f64 = 1e-5;
/// Relative Nelder–Mead tolerance of the default search's final refits on all rows (the
/// reported parameters).
pub const FAST_FINAL_TOLERANCE: f64 = 1e-6;
/// Nelder–Mead iteration cap per run (up to five parameters, in proportion beyond) of the
/// default search's screening fit of every candidate; those the held-out evidence leans to are
/// refined ([`SelectOptions::refine`]).
pub const SCREEN_ITERATIONS: u64 = 120;
/// Steps of each Metropolis chain of the default run's prediction bands (the thorough run:
/// [`uncertainty::CHAIN_STEPS`]; chains this short that disagree are run again at that length).
pub const FAST_CHAIN_STEPS: usize = 3000;

impl Options {
    /// Default options for a family, fast: all candidates, up to three effects; the baseline
    /// from the data's scales and one swarm start; each candidate screened by Nelder–Mead
    /// ([`SCREEN_ITERATIONS`], relative tolerance [`FAST_TOLERANCE`], one restart) from the
    /// current optimum and from it with the joint at the data's scales (no swarm,
    /// [`SelectOptions::joint_restart`]), every round's candidates in parallel and each fit
    /// evaluated at its training rows only; the candidates the held-out evidence leans to
    /// refined as the baseline is fitted (to the thorough tolerance, so that the model a round
    /// starts from and the candidates it accepts are converged alike); final refits to
    /// [`FAST_FINAL_TOLERANCE`]; chains of [`FAST_CHAIN_STEPS`] steps.
    pub fn new(family: Family) -> Self {
        let screen = FitOptions {
            starts: 0,
            restarts: 1,
            tolerance: FAST_TOLERANCE,
            local_iterations: SCREEN_ITERATIONS,
            ..FitOptions::default()
        };
        Self {
            family,
            fit_levels: None,
            select: SelectOptions {
                candidates: super::effects::Effect::ALL.to_vec(),
                max_effects: 3,
                baseline_fit: FitOptions {
                    starts: 1,
                    ..FitOptions::default()
                },
                candidate_fit: screen,
                training_rows_only: true,
                joint_restart: true,
                refine: Some(FitOptions {
                    starts: 0,
                    ..FitOptions::default()
                }),
            },
            final_fit: FitOptions {
                tolerance: FAST_FINAL_TOLERANCE,
                ..FitOptions::default()
            },
            response_amplitudes: None,
            chain_steps: FAST_CHAIN_STEPS,
            rows: FitRows::All,
        }
    }

    /// The thorough search (`--thorough`): three swarm starts for the baseline, one for each
    /// candidate beside its local start, Nelder–Mead to a relative tolerance of
    /// [`super::fit::THOROUGH_TOLERANCE`] with up to three restarts, every row evaluated, chains
    /// of [`uncertainty::CHAIN_STEPS`] steps.
    pub fn thorough(family: Family) -> Self {
        Self {
            select: SelectOptions {
                baseline_fit: FitOptions::default(),
                candidate_fit: FitOptions {
                    starts: 1,
                    ..FitOptions::default()
                },
                training_rows_only: false,
                joint_restart: false,
                refine: None,
                ..Self::new(family).select
            },
            final_fit: FitOptions::default(),
            chain_steps: uncertainty::CHAIN_STEPS,
            ..Self::new(family)
        }
    }

    /// Model evaluations the whole run is expected to take (progress-bar length): the
    /// baseline fit, up to `max_effects + 1` rounds of every candidate, the refits and the
    /// chains. Each stage's end re-plans the rest ([`Options::evaluations_after`]).
    pub fn estimated_evaluations(&self) -> u64 {
        let b = &self.select.baseline_fit;
        let dim = super::model::BASE_PARAMS;
        b.swarm_evaluations()
            + (b.starts as u64 + 1) * expected_local_evaluations(b, dim)
            + self.evaluations_after(Stage::Baseline, dim)
    }

    /// Evaluations expected after `stage` for a model of `dim` parameters at that point.
    pub fn evaluations_after(&self, stage: Stage, dim: usize) -> u64 {
        let c = &self.select.candidate_fit;
        let n = self.select.candidates.len() as u64;
        let rounds = self.select.max_effects as u64 + 1;
        let final_dim = dim + 2 * self.select.max_effects;
        // Local starts per candidate, and the share of candidates refined (a third, as on the
        // Brake–Reuss beam).
        let local_starts = 1 + u64::from(self.select.joint_restart);
        let candidate = c.swarm_evaluations()
            + local_starts * expected_local_evaluations(c, final_dim)
            + self
                .select
                .refine
                .map_or(0, |r| expected_local_evaluations(&r, final_dim) / 3);
        let refits = 3 * expected_local_evaluations(&self.final_fit, final_dim);
        let chains = (uncertainty::CHAINS * self.chain_steps + 2 * final_dim + 1) as u64;
        match stage {
            Stage::Baseline => rounds * n * candidate + refits + chains,
            Stage::Search => refits + chains,
            Stage::Refits => chains,
        }
    }
}

/// A stage of an identification after which the progress bar is re-planned.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Stage {
    /// Reading and the baseline fit are done; the effect search comes next.
    Baseline,
    /// The effect search is done; the refits on all rows of the fit levels come next.
    Search,
    /// The refits are done; only the Metropolis chains of the prediction bands remain.
    Refits,
}

/// Evaluations a Nelder–Mead fit of `dim` parameters is expected to take with `o`: about
/// 40 per parameter for a run to a relative tolerance of 10⁻⁵, 60 at 10⁻⁷, and half of that per
/// restart, up to the cap.
pub fn expected_local_evaluations(o: &FitOptions, dim: usize) -> u64 {
    let per = if o.tolerance >= 1e-5 { 40 } else { 60 } * dim as u64;
    let restarts = if o.tolerance >= 1e-5 { 1 } else { 2 }.min(o.restarts as u64);
    (per + restarts * per / 2).min(super::fit::local_iteration_cap(o.local_iterations, dim) * 2)
}

/// Set the progress bar's length to what is done plus `remaining`, and name the stage.
fn replan(progress: Option<&indicatif::ProgressBar>, remaining: u64, stage: &'static str) {
    if let Some(b) = progress {
        b.set_length(b.position() + remaining);
        b.set_message(stage);
    }
}

/// Wall time of one stage of a run.
#[derive(Debug, Clone, Serialize)]
pub struct StageTime {
    /// What the stage did, as printed in the report (e.g. "baseline fit and effect search").
    pub stage: &'static str,
    /// Wall-clock time the stage took (s).
    pub wall_time_s: f64,
}

/// The clock of a run's stages.
struct Stages {
    t: std::time::Instant,
    done: Vec<StageTime>,
}

impl Stages {
    fn new() -> Self {
        Self {
            t: std::time::Instant::now(),
            done: Vec::new(),
        }
    }

    /// Close the running stage under `name`.
    fn end(&mut self, name: &'static str) {
        self.done.push(StageTime {
            stage: name,
            wall_time_s: self.t.elapsed().as_secs_f64(),
        });
        self.t = std::time::Instant::now();
    }
}

/// Report lines of the stage times.
pub fn stage_times_text(stages: &[StageTime]) -> String {
    let mut s = String::from(
        "
time per stage (wall):
",
    );
    for t in stages {
        s += &format!("  {:<52} {:>8.1} s\n", t.stage, t.wall_time_s);
    }
    s
}

/// The response-controlled FRF of the identified model at one response amplitude.
#[derive(Debug, Clone, Serialize)]
pub struct ResponseControlled {
    /// Response amplitude held constant along the sweep, in the unit of `quantity` (m, m/s or
    /// m/s²).
    pub amplitude: f64,
    /// Which response `amplitude` and the FRF refer to (displacement, velocity or acceleration).
    pub quantity: Quantity,
    /// Excitation frequencies (Hz), 81 equally spaced over the measured band.
    pub frequency_hz: Vec<f64>,
    /// Drive force amplitude (N) that holds the response amplitude at each frequency.
    pub force_n: Vec<f64>,
    /// Response per unit force (the quantity's FRF, e.g. accelerance).
    #[serde(skip)]
    pub frf: Vec<Complex64>,
    /// `|frf|` at each frequency: response amplitude per newton (m/N, m/(s·N) or m/(s²·N)).
    pub frf_amplitude: Vec<f64>,
    /// Frequency of the FRF's peak (Hz), interpolated between the sampled frequencies.
    pub peak_frequency_hz: f64,
    /// FRF amplitude at the peak, in the unit of `frf_amplitude`.
    pub peak_frf: f64,
}

/// Everything an identification found.
#[derive(Debug, Clone)]
pub struct Identification {
    /// Sweeps by increasing mean force.
    pub sweeps: Vec<Sweep>,
    /// Phase convention of the measured files (detected, or as given).
    pub convention: PhaseConvention,
    /// 0-based indices into `sweeps`.
    pub fit_levels: Vec<usize>,
    /// Reference frequency, modal mass, amplitudes and force that make the model's parameters
    /// dimensionless.
    pub scales: Scales,
    /// Per level (in `sweeps` order): the backbone estimated from the measured sweep alone.
    pub data_backbone: Vec<LevelBackbone>,
    /// The held-out effect search: baseline, rounds, final spec and verdict.
    pub selection: Selection,
    /// Baseline and final models refitted on all rows of the fit levels.
    pub before: FitResult,
    /// Final model (baseline plus the accepted effects) refitted on all rows of the fit levels.
    pub after: FitResult,
    /// Per level (all levels): errors of the baseline and of the final model.
    pub errors_before: Vec<LevelErrors>,
    /// Per level: errors of the final model.
    pub errors_after: Vec<LevelErrors>,
    /// Parameter intervals and 95 % bands of the final model's predictions.
    pub uncertainty: Uncertainty,
    /// The model the held-out evidence leaned to without accepting it, refitted on all rows:
    /// the spread between its predictions and the final model's is model-form uncertainty.
    pub alternative: Option<Alternative>,
    /// The fit levels' own backbone interpolated in a single-nonlinear-mode response, no
    /// model: what the data alone predict for every level (or why it could not be built).
    pub model_free: std::result::Result<ModelFreeCheck, String>,
    /// Per level: its two sides at equal amplitude ([`stationarity::compare_sides`]; `None`
    /// where the sides have too few points at common amplitudes).
    pub stationarity: Vec<Option<SideComparison>>,
    /// When a fit level's sides differ: the model-free check on the settled rows (the earlier
    /// side of such levels left out) — what the data predict if only the settled part of those
    /// tests is trusted.
    pub model_free_settled: Option<std::result::Result<ModelFreeCheck, String>>,
    /// Per fit level (in `fit_levels` order): the first row (0-based, file order) fitted when
    /// only its settled rows are ([`FitRows::Settled`] on a level that is not stationary).
    pub settled_from: Vec<Option<usize>>,
    /// Backbone (natural frequency and damping versus displacement amplitude) of the baseline model
    /// over the measured amplitude range ([`model_backbone`]).
    pub backbone_before: Vec<BackbonePoint>,
    /// Backbone of the final model over the same amplitudes ([`model_backbone`]).
    pub backbone_after: Vec<BackbonePoint>,
    /// Response-controlled FRFs of the final model, one per requested response amplitude.
    pub response_controlled: Vec<ResponseControlled>,
    /// The options the identification ran with.
    pub options: Options,
    /// Wall time of each stage.
    pub stage_times: Vec<StageTime>,
    /// Wall-clock time of the whole identification (s).
    pub wall_time_s: f64,
}

/// Read sweeps and order them by mean force; a file that cannot be read is an error naming it.
pub fn read_sweeps(paths: &[PathBuf]) -> Result<Vec<Sweep>> {
    let mut sweeps = paths
        .iter()
        .map(|p| Sweep::read_csv(p))
        .collect::<Result<Vec<_>>>()?;
    // The same measurement given twice would count as two levels (and as its own held-out
    // evidence): refuse it, naming both files.
    for (i, a) in sweeps.iter().enumerate() {
        if let Some(b) = sweeps[..i].iter().find(|b| b.sha256 == a.sha256) {
            return Err(Error::Data(format!(
                "{} and {}: the same measurement (identical content) given twice; give each \
                 level's file once",
                b.path.display(),
                a.path.display()
            )));
        }
    }
    sweeps.sort_by(|a, b| a.mean_force_n().total_cmp(&b.mean_force_n()));
    Ok(sweeps)
}

/// Frequency span `(lowest, highest)` of a sweep's rows (Hz).
pub fn frequency_span(s: &Sweep) -> (f64, f64) {
    s.rows.iter().fold((f64::INFINITY, 0.0), |(lo, hi), r| {
        (lo.min(r.frequency_hz), hi.max(r.frequency_hz))
    })
}

/// Levels of one identification are sweeps of one mode surrounding the same resonance (files
/// of other modes are for `predict` with a reduced model): when the centres of the files'
/// frequency spans lie more than a factor 2 apart, one file is another mode or has its
/// frequencies in another unit. Refused, naming the file farthest from the median (both files
/// when there are two).
fn check_common_band(sweeps: &[Sweep]) -> Result<()> {
    if sweeps.len() < 2 {
        return Ok(());
    }
    let centre = |s: &Sweep| {
        let (lo, hi) = frequency_span(s);
        (lo * hi).sqrt()
    };
    let span = |s: &Sweep| {
        let (lo, hi) = frequency_span(s);
        format!("{} ({lo:.6}–{hi:.6} Hz)", s.path.display())
    };
    let why = "not the same mode, or frequencies in another unit (e.g. kHz in a `frequency_Hz` \
               column)";
    let mut centres: Vec<f64> = sweeps.iter().map(centre).collect();
    centres.sort_by(f64::total_cmp);
    if centres[centres.len() - 1] <= 2.0 * centres[0] {
        return Ok(());
    }
    if sweeps.len() == 2 {
        // Two files: no majority to say which one is off.
        return Err(Error::Data(format!(
            "{} and {}: frequency spans more than a factor 2 apart: {why}",
            span(&sweeps[0]),
            span(&sweeps[1])
        )));
    }
    let median = centres[centres.len() / 2];
    let worst = sweeps
        .iter()
        .max_by(|a, b| {
            (centre(a) / median)
                .ln()
                .abs()
                .total_cmp(&(centre(b) / median).ln().abs())
        })
        .expect("at least two sweeps");
    Err(Error::Data(format!(
        "{}: far from the other files' frequencies (around {median:.6} Hz; the spans lie more \
         than a factor 2 apart): {why}",
        span(worst)
    )))
}

fn names(sweeps: &[Sweep]) -> String {
    sweeps
        .iter()
        .map(|s| s.path.display().to_string())
        .collect::<Vec<_>>()
        .join(", ")
}

/// The fit levels (0-based) from the 1-based `--fit-levels` (`None`: lowest and highest),
/// checked against the sweeps (ordered by mean force).
pub fn choose_fit_levels(sweeps: &[Sweep], fit_levels: Option<&[usize]>) -> Result<Vec<usize>> {
    if sweeps.len() < 2 {
        return Err(Error::Data(format!(
            "{}: a single level; identification needs at least two excitation levels (the \
             joint's amplitude dependence separates it from the linear damping)",
            names(sweeps)
        )));
    }
    check_common_band(sweeps)?;
    let levels = match fit_levels {
        None => vec![0, sweeps.len() - 1],
        Some(v) => {
            let mut out = Vec::new();
            for &l in v {
                if l == 0 || l > sweeps.len() {
                    return Err(Error::param(
                        "--fit-levels",
                        format!("level {l} does not exist (levels 1..{})", sweeps.len()),
                    ));
                }
                if !out.contains(&(l - 1)) {
                    out.push(l - 1);
                }
            }
            out.sort_unstable();
            out
        }
    };
    if levels.len() < 2 {
        return Err(Error::param(
            "--fit-levels",
            format!(
                "a single level ({}) where at least two are needed to separate the joint from \
                 the linear damping",
                sweeps[levels[0]].path.display()
            ),
        ));
    }
    Ok(levels)
}

/// Drive-point displacement amplitude of the largest response per force of each sweep.
pub(crate) fn scales_from(sweeps: &[Sweep], fit: &[usize], bb: &[LevelBackbone]) -> Scales {
    let mut fres: Vec<f64> = fit.iter().map(|&i| bb[i].linear.frequency_hz).collect();
    fres.sort_by(|a, b| a.total_cmp(b));
    let amps: Vec<f64> = fit.iter().map(|&i| bb[i].peak_amplitude_m).collect();
    Scales {
        frequency_hz: fres[fres.len() / 2],
        modal_mass_kg: bb[fit[0]].linear.modal_mass_kg,
        amplitude_max_m: amps.iter().cloned().fold(0.0, f64::max),
        amplitude_min_m: amps.iter().cloned().fold(f64::INFINITY, f64::min),
        force_n: fit
            .iter()
            .map(|&i| sweeps[i].mean_force_n())
            .fold(0.0, f64::max),
    }
}

/// Check that a final fit converged and that the model solves every row of every level.
fn require_converged(fit: &FitResult, what: &str, levels: &[LevelData]) -> Result<()> {
    if !fit.converged {
        return Err(Error::NonConvergence {
            solver: format!(
                "identification fit ({what}, Nelder–Mead restarted from its optimum up to {} \
                 times, {} iterations in all)",
                super::fit::LOCAL_RESTARTS,
                fit.starts.first().map_or(0, |s| s.local_iterations)
            ),
            iterations: fit
                .starts
                .first()
                .map_or(0, |s| s.local_iterations as usize),
            residual: fit.cost,
            tolerance: 1e-7 * fit.cost,
        });
    }
    for l in levels {
        if let Err(e) = fit.model.receptance(&l.drives, l.mean_force_n) {
            // Name the line of the first failing row.
            let (_, fails) = fit
                .model
                .receptance_tolerant(&l.drives, l.mean_force_n, true)?;
            let line = fails.first().map_or(0, |f| l.lines[f.index]);
            return Err(Error::Data(format!(
                "{}:{line}: the {what} model has no harmonic-balance solution at this row: {e}",
                l.name
            )));
        }
    }
    Ok(())
}

/// Mean force at a drive-point amplitude, interpolated between the levels' (peak amplitude,
/// mean force) pairs (for the preload-loss effect on backbones).
fn force_at_amplitude(bb: &[LevelBackbone], a: f64) -> f64 {
    let mut pts: Vec<(f64, f64)> = bb
        .iter()
        .map(|b| (b.peak_amplitude_m, b.mean_force_n))
        .collect();
    pts.sort_by(|x, y| x.0.total_cmp(&y.0));
    if a <= pts[0].0 {
        return pts[0].1;
    }
    for w in pts.windows(2) {
        if a <= w[1].0 {
            let t = (a - w[0].0) / (w[1].0 - w[0].0).max(f64::MIN_POSITIVE);
            return w[0].1 + t * (w[1].1 - w[0].1);
        }
    }
    pts[pts.len() - 1].1
}

/// Model backbone over the measured amplitude range (40 points, log-spaced from half the
/// smallest to 1.5 × the largest level peak amplitude).
pub fn model_backbone(model: &Model, bb: &[LevelBackbone]) -> Result<Vec<BackbonePoint>> {
    let lo = bb
        .iter()
        .map(|b| b.peak_amplitude_m)
        .fold(f64::INFINITY, f64::min)
        * 0.5;
    let hi = bb.iter().map(|b| b.peak_amplitude_m).fold(0.0, f64::max) * 1.5;
    (0..40)
        .map(|i| {
            let a = lo * (hi / lo).powf(i as f64 / 39.0);
            let (f, z) = model.backbone_point(a, force_at_amplitude(bb, a))?;
            Ok(BackbonePoint {
                amplitude_m: a,
                frequency_hz: f,
                damping_ratio: z,
            })
        })
        .collect()
}

/// The model's response-controlled FRF at response amplitude `amplitude` of `quantity`, on 81
/// frequencies over `[f_lo, f_hi]`.
pub fn response_controlled(
    model: &Model,
    quantity: Quantity,
    amplitude: f64,
    band_hz: (f64, f64),
    mean_force_n: f64,
) -> Result<ResponseControlled> {
    response_controlled_with(quantity, amplitude, band_hz, |om, targets| {
        model.response_controlled(om, targets, mean_force_n)
    })
}

/// The response-controlled FRF at response amplitude `amplitude` of `quantity` on 81
/// frequencies over `[f_lo, f_hi]`, from a solver that returns, for angular frequencies and
/// target displacement amplitudes (m), the forces (N) that hold them and the receptances (m/N).
/// Shared by the single mode and the reduced models.
pub fn response_controlled_with(
    quantity: Quantity,
    amplitude: f64,
    band_hz: (f64, f64),
    solve: impl FnOnce(&[f64], &[f64]) -> Result<(Vec<f64>, Vec<Complex64>)>,
) -> Result<ResponseControlled> {
    let n = 81;
    let f: Vec<f64> = (0..n)
        .map(|i| band_hz.0 + (band_hz.1 - band_hz.0) * i as f64 / (n - 1) as f64)
        .collect();
    let om: Vec<f64> = f.iter().map(|x| TAU * x).collect();
    let targets: Vec<f64> = om
        .iter()
        .map(|&w| amplitude / quantity.from_displacement(w).norm())
        .collect();
    let (forces, x) = solve(&om, &targets)?;
    let frf: Vec<Complex64> = x
        .iter()
        .zip(&om)
        .map(|(xi, &w)| xi * quantity.from_displacement(w))
        .collect();
    let amp: Vec<f64> = frf.iter().map(|v| v.norm()).collect();
    let (pf, pa) = backbone::resonance(&f, &amp);
    Ok(ResponseControlled {
        amplitude,
        quantity,
        frequency_hz: f,
        force_n: forces,
        frf,
        frf_amplitude: amp,
        peak_frequency_hz: pf,
        peak_frf: pa,
    })
}

/// The response amplitudes at which an identified model's response-controlled FRF is reported
/// (`given`, or the measured peak response of every level, in the unit of its quantity) and the
/// frequency band of all the measured rows (Hz).
pub fn response_control_amplitudes(
    sweeps: &[Sweep],
    given: Option<&[f64]>,
) -> (Vec<f64>, (f64, f64)) {
    let amplitudes = match given {
        Some(a) => a.to_vec(),
        None => sweeps
            .iter()
            .map(|s| s.rows[s.peak_row()].response)
            .collect(),
    };
    let band = sweeps
        .iter()
        .flat_map(|s| &s.rows)
        .fold((f64::INFINITY, 0.0f64), |(a, b), r| {
            (a.min(r.frequency_hz), b.max(r.frequency_hz))
        });
    (amplitudes, band)
}

/// Report lines of the response-controlled FRFs.
pub fn response_controlled_text(rows: &[ResponseControlled]) -> String {
    let mut s = "\nidentified model under response control (response amplitude held, force solved \
                 for):\n"
        .to_string();
    for r in rows {
        s += &format!(
            "  response amplitude {} {}: peak {} {} ({}/N) at {:.3} Hz\n",
            significant(r.amplitude),
            r.quantity.unit(),
            r.quantity.frf_name(),
            significant(r.peak_frf),
            r.quantity.unit(),
            r.peak_frequency_hz
        );
    }
    s
}

/// Five significant digits, fixed-point for magnitudes 1e-2 to 1e5 (accelerations, accelerances)
/// and in exponent form otherwise (displacements in m, receptances in m/N).
fn significant(x: f64) -> String {
    let a = x.abs();
    if a == 0.0 || (1e-2..1e5).contains(&a) {
        let decimals = (4 - a.log10().floor() as i32).clamp(0, 6) as usize;
        format!("{x:.decimals$}")
    } else {
        format!("{x:.4e}")
    }
}

/// `identify-response-controlled.csv`: the identified model's FRF at each held response
/// amplitude, row by row.
pub fn write_response_controlled_csv(path: &Path, rows: &[ResponseControlled]) -> Result<()> {
    write_atomic(path, |w| {
        let io = |e| Error::io(path, e);
        writeln!(w, "# identified (final) model under response control: the response amplitude is held, the force solved for; FRF = response per unit force in the model's phase convention (e^(i omega t))").map_err(io)?;
        writeln!(
            w,
            "response_amplitude,unit,frequency_Hz,force_amplitude_N,frf_amplitude,frf_phase_rad"
        )
        .map_err(io)?;
        for r in rows {
            for k in 0..r.frequency_hz.len() {
                writeln!(
                    w,
                    "{},{},{},{:.6e},{:.6e},{:.6e}",
                    r.amplitude,
                    r.quantity.unit(),
                    r.frequency_hz[k],
                    r.force_n[k],
                    r.frf_amplitude[k],
                    r.frf[k].arg()
                )
                .map_err(io)?;
            }
        }
        Ok(())
    })
}

/// The backbone files of both identify paths in `dir`: `identify-backbone.csv` and, where the
/// data gave estimates, `identify-backbone.png` — the data's backbone, the models' (`(CSV source
/// name, legend label, points)`) and the model-free laws' of `check`
/// ([`model_free::law_curves`]: source name and label their id).
pub fn write_backbone_files(
    dir: &Path,
    data: &[LevelBackbone],
    models: [(&str, &str, Vec<BackbonePoint>); 2],
    check: &std::result::Result<ModelFreeCheck, String>,
) -> Result<Vec<PathBuf>> {
    let mut curves: Vec<(String, String, Vec<BackbonePoint>)> = models
        .into_iter()
        .map(|(id, label, points)| (id.to_string(), label.to_string(), points))
        .collect();
    curves.extend(
        model_free::law_curves(check)
            .into_iter()
            .map(|(id, points)| (id.clone(), id, points)),
    );
    let mut written = Vec::new();
    let p = dir.join("identify-backbone.csv");
    let rows: Vec<(&str, &[BackbonePoint])> = curves
        .iter()
        .map(|(id, _, points)| (id.as_str(), points.as_slice()))
        .collect();
    write_backbone_csv(&p, data, &rows)?;
    written.push(p);
    if !data.is_empty() {
        let p = dir.join("identify-backbone.png");
        let labelled: Vec<(String, Vec<BackbonePoint>)> = curves
            .into_iter()
            .map(|(_, label, points)| (label, points))
            .collect();
        plot_backbone(&p, data, &labelled)?;
        written.push(p);
    }
    Ok(written)
}

/// `identify-backbone.csv`: the data's backbone (equivalent linear mode per level and pointwise
/// estimates) and the models' (`(source name, points)`).
pub fn write_backbone_csv(
    path: &Path,
    data: &[LevelBackbone],
    models: &[(&str, &[BackbonePoint])],
) -> Result<()> {
    write_atomic(path, |w| {
        let io = |e| Error::io(path, e);
        writeln!(w, "# backbone: drive-point displacement amplitude (m), natural frequency (Hz), damping ratio (-)").map_err(io)?;
        writeln!(w, "source,amplitude_m,frequency_Hz,damping_ratio").map_err(io)?;
        for b in data {
            writeln!(
                w,
                "data-level-{},{:.6e},{:.6},{:.6e}",
                b.file, b.peak_amplitude_m, b.linear.frequency_hz, b.linear.damping_ratio
            )
            .map_err(io)?;
            for q in &b.points {
                writeln!(
                    w,
                    "data-pointwise-{},{:.6e},{:.6},{:.6e}",
                    b.file, q.amplitude_m, q.frequency_hz, q.damping_ratio
                )
                .map_err(io)?;
            }
        }
        for (name, bb) in models {
            for q in bb.iter() {
                writeln!(
                    w,
                    "{name},{:.6e},{:.6},{:.6e}",
                    q.amplitude_m, q.frequency_hz, q.damping_ratio
                )
                .map_err(io)?;
            }
        }
        Ok(())
    })
}

/// Errors of a model at every level.
fn level_errors(model: &Model, levels: &[LevelData], fit: &[usize]) -> Result<Vec<LevelErrors>> {
    levels
        .iter()
        .enumerate()
        .map(|(i, l)| {
            let (y, failed) = l.model_frf(model)?;
            let role = level_role(i, fit);
            Ok(LevelErrors::new(l, &y, role, failed))
        })
        .collect()
}

/// A model the held-out evidence does not exclude.
#[derive(Debug, Clone, Serialize)]
pub struct Alternative {
    /// Effects the alternative adds to the baseline.
    pub effects: Vec<super::effects::Effect>,
    /// Held-out ΔBIC against the final model (negative: the evidence leans to it, but not past
    /// the threshold).
    pub delta_bic: f64,
    /// Its refit on all rows of the fit levels.
    pub fit: FitResult,
    /// Per level: its errors (fit levels and predicted levels).
    pub errors: Vec<LevelErrors>,
}

/// The strongest refused candidate of the search's last round with `ΔBIC < 0`, refitted on all
/// rows of the fit levels; `None` when the search stopped on `max_effects` (the last round then
/// accepted an effect, and its other candidates extend the previous model, not the final one)
/// or no candidate had `ΔBIC < 0`. An alternative whose refit does not converge is left out.
fn alternative(
    selection: &Selection,
    fit_data: &[LevelData],
    levels: &[LevelData],
    fit_levels: &[usize],
    opts: &Options,
    progress: Option<&indicatif::ProgressBar>,
) -> Result<Option<Alternative>> {
    let Some(last) = selection.rounds.last().filter(|r| r.accepted.is_none()) else {
        return Ok(None);
    };
    let Some(c) = last
        .candidates
        .iter()
        .filter(|c| c.delta_bic < 0.0)
        .min_by(|a, b| a.delta_bic.total_cmp(&b.delta_bic))
    else {
        return Ok(None);
    };
    let fit = refit_all_rows::<ModelSpec>(&c.fit, fit_data, &opts.final_fit, progress)?;
    if !fit.converged {
        return Ok(None);
    }
    Ok(Some(Alternative {
        effects: fit.model.spec.effects.clone(),
        delta_bic: c.delta_bic,
        errors: level_errors(&fit.model, levels, fit_levels)?,
        fit,
    }))
}

/// Run an identification on measured sweeps (any order; they are sorted by mean force).
pub fn identify(
    sweeps: Vec<Sweep>,
    opts: &Options,
    progress: Option<&indicatif::ProgressBar>,
) -> Result<Identification> {
    let t0 = std::time::Instant::now();
    let mut stages = Stages::new();
    let mut sweeps = sweeps;
    sweeps.sort_by(|a, b| a.mean_force_n().total_cmp(&b.mean_force_n()));
    let fit_levels = choose_fit_levels(&sweeps, opts.fit_levels.as_deref())?;
    let convention = PhaseConvention::detect_common(&sweeps)?;
    let frfs: Vec<Vec<Complex64>> = sweeps.iter().map(|s| s.frf(&convention)).collect();
    let data_backbone = backbone::from_data(&sweeps, &frfs)?;
    let scales = scales_from(&sweeps, &fit_levels, &data_backbone);
    let levels: Vec<LevelData> = sweeps
        .iter()
        .map(|s| LevelData::new(s, &convention))
        .collect();
    let stationarity = stationarity::compare_levels(&data_backbone, &levels);
    let settled_from = settled_first_rows(&fit_levels, &stationarity, &data_backbone, opts.rows);
    let fit_data: Vec<LevelData> = fit_levels
        .iter()
        .zip(&settled_from)
        .map(|(&i, first)| first.map_or_else(|| levels[i].clone(), |r| levels[i].from_row(r)))
        .collect();
    let baseline = ModelSpec::baseline(opts.family, scales);
    stages.end("reading, backbones, stationarity");
    if let Some(b) = progress {
        b.set_message("baseline fit and effect search");
    }
    let selection = select::select(
        &baseline,
        &select::neutral_start(&baseline),
        &fit_data,
        &opts.select,
        progress,
    )?;
    stages.end("baseline fit and effect search");
    replan(
        progress,
        opts.evaluations_after(Stage::Search, selection.final_train_fit.model.values.len()),
        "refits on all rows",
    );
    let before = refit_all_rows::<ModelSpec>(
        &selection.baseline_train_fit,
        &fit_data,
        &opts.final_fit,
        progress,
    )?;
    require_converged(&before, "baseline", &levels)?;
    let after = if selection.final_spec == baseline {
        before.clone()
    } else {
        let a = refit_all_rows::<ModelSpec>(
            &selection.final_train_fit,
            &fit_data,
            &opts.final_fit,
            progress,
        )?;
        let ids: Vec<&str> = a.model.spec.effects.iter().map(|e| e.id()).collect();
        require_converged(&a, &format!("final, effects {}", ids.join(" + ")), &levels)?;
        a
    };
    let alternative = alternative(&selection, &fit_data, &levels, &fit_levels, opts, progress)?;
    stages.end("refits on all rows (baseline, final, alternative)");
    let errors_before = level_errors(&before.model, &levels, &fit_levels)?;
    let errors_after = level_errors(&after.model, &levels, &fit_levels)?;
    let model_free = model_free::check(&sweeps, &frfs, &levels, &fit_levels, &errors_after)
        .map_err(|e| e.to_string());
    let model_free_settled = model_free::check_settled(
        &sweeps,
        &frfs,
        &levels,
        &fit_levels,
        &errors_after,
        &stationarity,
    );
    stages.end("model-free check");
    replan(
        progress,
        opts.evaluations_after(Stage::Refits, after.model.values.len()),
        "prediction bands (Metropolis chains)",
    );
    let roles = level_roles(levels.len(), &fit_levels);
    let uncertainty = uncertainty::estimate(
        &after.model.spec,
        &after.model,
        &fit_data,
        &levels,
        &roles,
        opts.chain_steps,
        progress,
    );
    stages.end("prediction bands (Metropolis chains)");
    let backbone_before = model_backbone(&before.model, &data_backbone)?;
    let backbone_after = model_backbone(&after.model, &data_backbone)?;
    let quantity = sweeps[0].quantity;
    let (amplitudes, (flo, fhi)) =
        response_control_amplitudes(&sweeps, opts.response_amplitudes.as_deref());
    let response_controlled = amplitudes
        .iter()
        .map(|&a| {
            crate::core::error::require_positive("--response-amplitude", a)?;
            response_controlled(&after.model, quantity, a, (flo, fhi), scales.force_n)
        })
        .collect::<Result<Vec<_>>>()?;
    stages.end("backbones, response control");
    Ok(Identification {
        sweeps,
        convention,
        fit_levels,
        scales,
        data_backbone,
        selection,
        before,
        after,
        errors_before,
        errors_after,
        uncertainty,
        alternative,
        model_free,
        stationarity,
        settled_from,
        model_free_settled,
        backbone_before,
        backbone_after,
        response_controlled,
        options: opts.clone(),
        stage_times: stages.done,
        wall_time_s: t0.elapsed().as_secs_f64(),
    })
}

/// The report's line on fit level `level` (0-based) fitted on its settled rows only: from its
/// resonance row on (file line `line` at `frequency_hz`), `kept` of its `total` rows.
pub(crate) fn settled_rows_line(
    level: usize,
    line: usize,
    frequency_hz: f64,
    kept: usize,
    total: usize,
) -> String {
    format!(
        "fit rows (--rows settled): level {} is not stationary (see below); fitted from its \
         resonance row on, line {line} ({frequency_hz:.2} Hz), {kept} of {total} rows\n",
        level + 1
    )
}

/// Per fit level: the first row to fit when only settled rows are ([`FitRows::Settled`] and
/// the level's sides differ), else `None` (every row).
pub(crate) fn settled_first_rows(
    fit_levels: &[usize],
    sides: &[Option<SideComparison>],
    backbones: &[LevelBackbone],
    rows: FitRows,
) -> Vec<Option<usize>> {
    fit_levels
        .iter()
        .map(|&i| {
            let unsettled = sides[i].as_ref().is_some_and(|c| !c.stationary);
            (rows == FitRows::Settled && unsettled).then_some(backbones[i].resonance_row)
        })
        .collect()
}

/// The saved model file (`model.json`): everything `asperity predict` needs.
#[derive(Debug, Clone, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SavedModel {
    /// Format tag, always [`MODEL_FORMAT`].
    pub format: String,
    /// Version of the file layout (1).
    pub version: u32,
    /// The identified model: its spec and parameter values (physical units, see `parameters`).
    pub model: Model,
    /// Phase convention of the measurements it was identified from (used by `predict` when a
    /// file's own convention cannot be detected).
    pub phase_convention: PhaseConvention,
    /// Parameters with names, units and bounds (for reading; `model` is authoritative).
    pub parameters: Vec<serde_json::Value>,
    /// The measured files of the fit levels, each as `{"path", "sha256"}`.
    pub identified_from: Vec<serde_json::Value>,
    /// Models of the same form that fit the fit levels about as well, with weights (for the
    /// 95 % bands of `asperity predict`, `uncertainty.rs`); absent where they could not be
    /// sampled and in files written before they were saved.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub ensemble: Option<Ensemble>,
}

/// Format tag of [`SavedModel`].
pub const MODEL_FORMAT: &str = "asperity-identified-model";

impl SavedModel {
    /// The model file of an identification: its final model, phase convention, parameter table,
    /// fit-level files and ensemble.
    pub fn new(id: &Identification) -> Self {
        let m = &id.after.model;
        Self {
            format: MODEL_FORMAT.into(),
            version: 1,
            model: m.clone(),
            phase_convention: id.convention,
            parameters: parameter_table(m),
            identified_from: id
                .fit_levels
                .iter()
                .map(|&i| {
                    let s = &id.sweeps[i];
                    serde_json::json!({"path": s.path, "sha256": s.sha256})
                })
                .collect(),
            ensemble: match &id.uncertainty {
                Uncertainty::Estimated(e) => Some(e.ensemble.clone()),
                Uncertainty::NotEstimated { .. } => None,
            },
        }
    }

    /// Read and validate a saved model (format, version, parameter count and bounds).
    pub fn read(path: &Path) -> Result<Self> {
        let text = std::fs::read_to_string(path).map_err(|e| Error::io(path, e))?;
        let s: SavedModel = serde_json::from_str(&text).map_err(|e| {
            Error::parse(path, e.line(), format!("not an identified model file: {e}"))
        })?;
        if s.format != MODEL_FORMAT || s.version != 1 {
            return Err(Error::parse(
                path,
                0,
                format!(
                    "format {:?} version {} (expected {MODEL_FORMAT:?} version 1)",
                    s.format, s.version
                ),
            ));
        }
        s.phase_convention
            .check()
            .map_err(|e| Error::parse(path, 0, format!("phase_convention.{e}")))?;
        s.model
            .spec
            .scales
            .check()
            .map_err(|e| Error::parse(path, 0, format!("model.spec.scales.{e}")))?;
        Model::new(s.model.spec.clone(), s.model.values.clone())
            .map_err(|e| Error::parse(path, 0, e.to_string()))?;
        if let Some(e) = &s.ensemble {
            e.check(&s.model.spec.params())
                .map_err(|e| Error::parse(path, 0, e))?;
        }
        Ok(s)
    }
}

/// Parameters with units and bounds, for JSON.
pub fn parameter_table(m: &Model) -> Vec<serde_json::Value> {
    m.spec
        .params()
        .iter()
        .zip(&m.values)
        .map(|(p, v)| {
            serde_json::json!({"name": p.name, "unit": p.unit, "value": v, "lower_bound": p.lo,
                "upper_bound": p.hi, "at_bound": super::model::at_bound(p, *v)})
        })
        .collect()
}

fn params_text(m: &Model) -> String {
    let ph = m.physical();
    let mut s = String::new();
    for (p, v) in m.spec.params().iter().zip(&m.values) {
        s += &format!(
            "    {:<42} {:>12.5e} {:<3} [{:.3e}, {:.3e}]{}\n",
            p.name,
            v,
            p.unit,
            p.lo,
            p.hi,
            if super::model::at_bound(p, *v) {
                "  (at a bound)"
            } else {
                ""
            }
        );
    }
    s += &format!(
        "    → joint stick stiffness k_t = {:.4e} N/m, slip force F_s = {:.4e} N, linear stiffness \
         k = {:.4e} N/m, c = {:.4e} N·s/m (drive point)\n",
        ph.k_joint, ph.slip_force_n, ph.k_linear, ph.c_linear
    );
    s
}

/// The search's rounds as a table per round: every candidate's training and held-out
/// objective, ΔBIC and whether every fit level improved, the accepted one marked.
pub fn rounds_text<M>(rounds: &[Round<M>]) -> String {
    let mut s = String::new();
    for (k, r) in rounds.iter().enumerate() {
        s += &format!(
            "\nround {}: base effects [{}], held-out J = {:.4e}, lag-1 autocorrelation {:.2}, \
                 n_eff = {:.1}\n",
            k + 1,
            r.base_effects
                .iter()
                .map(|e| e.id())
                .collect::<Vec<_>>()
                .join(", "),
            r.base_held_out.cost,
            r.lag1_autocorrelation,
            r.effective_samples
        );
        s += &format!(
            "  {:<41} {:>3} {:>12} {:>12} {:>10} {:>11}\n",
            "candidate", "Δp", "train J", "held-out J", "ΔBIC", "all levels"
        );
        for c in &r.candidates {
            s += &format!(
                "  {:<41} {:>3} {:>12.4e} {:>12.4e} {:>10.1} {:>11}{}\n",
                match c.jointly_with {
                    Some(w) => format!("{} + {}", c.effect.id(), w.id()),
                    None => c.effect.id().to_string(),
                },
                c.added_parameters,
                c.train_cost,
                c.held_out.cost,
                c.delta_bic,
                if c.improves_every_level {
                    "better"
                } else {
                    "not all"
                },
                match (
                    r.accepted == Some(c.effect) && r.accepted_with == c.jointly_with,
                    c.generalises,
                ) {
                    (true, Some(n)) => format!("  ← accepted, replaces {}", n.id()),
                    (true, None) => "  ← accepted".to_string(),
                    (false, Some(n)) => format!("  (generalises {})", n.id()),
                    (false, None) => String::new(),
                }
            );
        }
    }
    s
}

/// Text of the verdict.
pub fn verdict_text(v: &Verdict) -> String {
    match v {
        Verdict::EffectsFound {
            effects,
            at_scatter,
        } => format!(
            "effect(s) accepted on held-out evidence: {}{}",
            effects
                .iter()
                .map(|e| format!("{} ({})", e.id(), e.meaning()))
                .collect::<Vec<_>>()
                .join("; "),
            if *at_scatter {
                "; the final held-out residual is within the measurement scatter"
            } else {
                "; the final held-out residual is still above the measurement scatter: part of \
                 the misfit is not explained by any candidate"
            }
        ),
        Verdict::NoEffectNeeded => {
            "no effect needed: the baseline's held-out residual is within the measurement scatter"
                .into()
        }
        Verdict::Unexplained {
            held_out_cost,
            scatter_floor,
        } => format!(
            "the residual stays above the measurement scatter (held-out RMS {:.3} vs scatter \
             {:.3}, relative to the peaks) and no candidate effect explains it on held-out \
             evidence: none is forced",
            held_out_cost.sqrt(),
            scatter_floor.sqrt()
        ),
    }
}

impl Identification {
    /// Human-readable report.
    pub fn text(&self) -> String {
        let mut s = String::from(
            "asperity identify — single-nonlinear-mode model from measured frequency responses\n\n",
        );
        s += "levels (by increasing mean force):\n";
        for (i, sw) in self.sweeps.iter().enumerate() {
            s += &format!(
                "  {} {} ({} rows, {}, mean force {:.4} N, sha256 {}) — {}\n",
                i + 1,
                sw.path.display(),
                sw.rows.len(),
                sw.quantity.column(),
                sw.mean_force_n(),
                &sw.sha256[..16],
                level_role(i, &self.fit_levels)
            );
        }
        s += &format!(
            "phase convention detected: {}\n",
            self.convention.describe()
        );
        for (&i, first) in self.fit_levels.iter().zip(&self.settled_from) {
            if let Some(r) = first {
                let sw = &self.sweeps[i];
                let row = &sw.rows[*r];
                s += &settled_rows_line(
                    i,
                    row.line,
                    row.frequency_hz,
                    sw.rows.len() - r,
                    sw.rows.len(),
                );
            }
        }
        s += &format!(
            "objective: complex response per unit force, residual / each level's peak, levels \
             weighted alike; training rows = even rows of the fit levels, held-out = odd rows\n\
             measurement scatter (third differences, relative to the peak): {}\n\n",
            self.selection
                .relative_scatter_per_level
                .iter()
                .map(|v| format!("{:.4}", v))
                .collect::<Vec<_>>()
                .join(", ")
        );
        let b = &self.selection.baseline_train_fit;
        s += &format!(
            "baseline ({:?} joint) on training rows: J = {:.4e}, {} starts (final costs {}), {} \
             evaluations, {:.1} s\n",
            self.options.family,
            b.cost,
            b.starts.len(),
            b.starts
                .iter()
                .map(|x| format!("{:.4e}", x.final_cost))
                .collect::<Vec<_>>()
                .join(", "),
            b.evaluations,
            b.wall_time_s
        );
        s += &rounds_text(&self.selection.rounds);
        s += &format!("\nverdict: {}\n", verdict_text(&self.selection.verdict));
        s += &format!(
            "\nbaseline refitted on all rows of the fit levels (J = {:.4e}):\n{}",
            self.before.cost,
            params_text(&self.before.model)
        );
        s += &format!(
            "final model [{}] refitted on all rows (J = {:.4e}):\n{}\n",
            self.after
                .model
                .spec
                .effects
                .iter()
                .map(|e| e.id())
                .collect::<Vec<_>>()
                .join(", "),
            self.after.cost,
            params_text(&self.after.model)
        );
        let rows: Vec<_> = self
            .errors_before
            .iter()
            .zip(&self.errors_after)
            .map(|(b, a)| (b, Some(a)))
            .collect();
        s += &errors_table(
            "errors per level, baseline → final model (resonance and peak of the response per unit force):",
            &rows,
        );
        s += &self.uncertainty.text("final model");
        if let Some(a) = &self.alternative {
            s +=
                &format!(
                "\nalternative the held-out evidence does not exclude: [{}] (held-out ΔBIC {:.1} \
                 against the final model, threshold {:.0}), refitted on all rows (J = {:.4e}):\n{}",
                a.effects.iter().map(|e| e.id()).collect::<Vec<_>>().join(", "),
                a.delta_bic,
                select::BIC_THRESHOLD,
                a.fit.cost,
                params_text(&a.fit.model)
            );
            let rows: Vec<_> = self
                .errors_after
                .iter()
                .zip(&a.errors)
                .map(|(f, a)| (f, Some(a)))
                .collect();
            s += &errors_table(
                "errors per level, final model → alternative (their spread on the levels not used \
                 is the model-form uncertainty the fit levels leave):",
                &rows,
            );
        }
        s += &stationarity::levels_section(&self.stationarity, &self.fit_levels);
        s += &model_free::section(&self.model_free, &self.errors_after);
        if let Some(settled) = &self.model_free_settled {
            s += &model_free::section(settled, &self.errors_after);
        }
        let rows: Vec<(&LevelErrors, Option<&LevelErrors>)> =
            self.errors_after.iter().map(|e| (e, None)).collect();
        s += &regions_text("final model, residual per region", &rows);
        s += "\nbackbone: data (equivalent linear mode per level) beside the final model at the \
              same amplitude:\n";
        for b in &self.data_backbone {
            let fm = force_at_amplitude(&self.data_backbone, b.peak_amplitude_m);
            let (f, z) = self
                .after
                .model
                .backbone_point(b.peak_amplitude_m, fm)
                .unwrap_or((f64::NAN, f64::NAN));
            s += &format!(
                "  {}: amplitude {:.3e} m: data {:.3} Hz, ζ = {:.5} | model {:.3} Hz, ζ = {:.5}\n",
                b.file, b.peak_amplitude_m, b.linear.frequency_hz, b.linear.damping_ratio, f, z
            );
        }
        s += &response_controlled_text(&self.response_controlled);
        s += &stage_times_text(&self.stage_times);
        s += &format!("\nwall time {:.1} s\n", self.wall_time_s);
        s
    }

    /// Write every output into `dir`; returns the paths written.
    pub fn write(&self, dir: &Path) -> Result<Vec<PathBuf>> {
        let mut written = Vec::new();
        let levels: Vec<LevelData> = self
            .sweeps
            .iter()
            .map(|s| LevelData::new(s, &self.convention))
            .collect();
        // Per-row CSV.
        let mut rows = Vec::new();
        for (i, (l, sw)) in levels.iter().zip(&self.sweeps).enumerate() {
            let (yb, _) = l.model_frf(&self.before.model)?;
            let (ya, _) = l.model_frf(&self.after.model)?;
            let role = level_role(i, &self.fit_levels);
            for (k, r) in sw.rows.iter().enumerate() {
                rows.push(CurveRow {
                    file: l.name.clone(),
                    role: role.into(),
                    line: r.line,
                    frequency_hz: r.frequency_hz,
                    force_n: r.force_n,
                    measured: l.measured[k],
                    models: vec![yb[k], ya[k]],
                });
            }
        }
        let p = dir.join("identify-rows.csv");
        let conv = self.convention;
        write_rows_csv(
            &p,
            "response per unit force in the unit of each file's quantity per N; phases in the files' convention; baseline and final model at the measured rows and forces",
            &["baseline", "final"],
            &rows,
            &|_| conv,
        )?;
        written.push(p);
        // Figures per level.
        for (i, l) in levels.iter().enumerate() {
            let role = if self.fit_levels.contains(&i) {
                "fitted"
            } else {
                "predicted"
            };
            let curves = vec![
                (
                    format!("baseline ({role})"),
                    fine_curve(&self.before.model, l, 4),
                ),
                (
                    format!("final ({role})"),
                    fine_curve(&self.after.model, l, 4),
                ),
            ];
            let p = dir.join(format!("identify-level{}.png", i + 1));
            let title = format!("level {} ({}), {role}", i + 1, l.name);
            plot_level(&p, l, &self.convention, &curves, &title)?;
            written.push(p);
        }
        // Backbones.
        written.extend(write_backbone_files(
            dir,
            &self.data_backbone,
            [
                (
                    "baseline-model",
                    "baseline model",
                    self.backbone_before.clone(),
                ),
                ("final-model", "final model", self.backbone_after.clone()),
            ],
            &self.model_free,
        )?);
        // Response-controlled FRFs.
        let p = dir.join("identify-response-controlled.csv");
        write_response_controlled_csv(&p, &self.response_controlled)?;
        written.push(p);
        // Model file.
        let p = dir.join("model.json");
        write_json(&p, &SavedModel::new(self))?;
        written.push(p);
        // JSON report.
        let p = dir.join("identify.json");
        let model_free_json =
            super::report::available_or_reason(&self.model_free, serde_json::value::Serializer)
                .map_err(|e| Error::Data(format!("{}: cannot serialise: {e}", p.display())))?;
        let model_free_settled_json = super::report::optional_available_or_reason(
            &self.model_free_settled,
            serde_json::value::Serializer,
        )
        .map_err(|e| Error::Data(format!("{}: cannot serialise: {e}", p.display())))?;
        let json = serde_json::json!({
            "tool": "asperity identify",
            "crate_version": env!("CARGO_PKG_VERSION"),
            "units": "SI: frequencies Hz, forces N, displacements m; FRFs in the unit of each file's quantity per N; errors relative to each level's measured peak",
            "inputs": self.sweeps.iter().map(InputFile::of).collect::<Vec<_>>(),
            "levels_fit": self.fit_levels.iter().map(|i| i + 1).collect::<Vec<_>>(),
            "fit_rows": self.fit_levels.iter().zip(&self.settled_from).map(|(&i, first)| serde_json::json!({
                "level": i + 1,
                "first_line": self.sweeps[i].rows[first.unwrap_or(0)].line,
                "rows": self.sweeps[i].rows.len() - first.unwrap_or(0),
                "settled_only": first.is_some(),
            })).collect::<Vec<_>>(),
            "phase_convention": {"value": self.convention, "description": self.convention.describe()},
            "scales": self.scales,
            "options": self.options,
            "method": {
                "model": "single mass-normalised mode + joint element on the modal coordinate (drive-point form m u'' + c u' + k u + f_joint(u) + effects = F cos wt), harmonic balance with odd harmonics 1,3 (1..9 with higher_harmonics), warm starts along each sweep",
                "objective": "mean over levels of mean over rows of |Y_model - Y_meas|^2 / max|Y_meas|^2 (complex response per unit force)",
                "search": "argmin particle swarm (seeded xoshiro256++) then Nelder-Mead restarted from its optimum, several starts (settings in 'options'); bounds in 'parameters'",
                "selection": "training = even rows, held-out = odd rows of the fit levels; held-out dBIC with AR(1) effective sample size < -10 and every fit level better",
                "scatter": "median |third difference| / (1.1774 sqrt(20)) per level"
            },
            "data_backbone": self.data_backbone,
            "selection": self.selection,
            "verdict_text": verdict_text(&self.selection.verdict),
            "baseline": {"fit": self.before, "parameters": parameter_table(&self.before.model), "backbone": self.backbone_before},
            "final": {"fit": self.after, "parameters": parameter_table(&self.after.model), "backbone": self.backbone_after},
            "errors_before": self.errors_before,
            "errors_after": self.errors_after,
            "uncertainty": self.uncertainty,
            "alternative": self.alternative,
            "model_free": model_free_json,
            "stationarity": {"criterion": stationarity::criterion_json(), "levels": self.stationarity},
            "model_free_settled_rows": model_free_settled_json,
            "response_controlled": self.response_controlled.iter().map(|r| serde_json::json!({
                "amplitude": r.amplitude, "unit": r.quantity.unit(), "peak_frf": r.peak_frf, "peak_frequency_Hz": r.peak_frequency_hz
            })).collect::<Vec<_>>(),
            "stage_times": self.stage_times,
            "wall_time_s": self.wall_time_s,
        });
        write_json(&p, &json)?;
        written.push(p);
        let p = dir.join("identify.txt");
        write_string_atomic(&p, &self.text())?;
        written.push(p);
        Ok(written)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The model files under docs/ (written by this code) read; a misspelled key, a time sign
    /// that is not ±1 and a non-positive scale are refused naming the file and the field.
    #[test]
    fn saved_model_files_are_read_strictly() {
        let root = Path::new(env!("CARGO_MANIFEST_DIR"));
        for f in [
            "calib/identify/model.json",
            "calib/identify-settled/model.json",
        ] {
            SavedModel::read(&root.join(f)).unwrap();
        }
        let good: serde_json::Value = serde_json::from_str(
            &std::fs::read_to_string(root.join("calib/identify/model.json")).unwrap(),
        )
        .unwrap();
        let d = tempfile::tempdir().unwrap();
        type Edit = fn(&mut serde_json::Value);
        let cases: [(Edit, &str); 6] = [
            (
                |v| {
                    let e = v.as_object_mut().unwrap().remove("ensemble").unwrap();
                    v["ensembel"] = e;
                },
                "unknown field `ensembel`",
            ),
            (
                |v| v["model"]["spec"]["scales"]["extra"] = 3.into(),
                "unknown field `extra`",
            ),
            (
                |v| v["phase_convention"]["time_sign"] = 0.5.into(),
                "phase_convention.time_sign = 0.5",
            ),
            (
                |v| v["model"]["spec"]["scales"]["force_n"] = (-1.0).into(),
                "model.spec.scales.force_n = -1",
            ),
            (
                |v| v["model"]["spec"]["scales"]["amplitude_max_m"] = 0.0.into(),
                "model.spec.scales.amplitude_max_m = 0",
            ),
            (
                |v| v["model"]["spec"]["scales"]["modal_mass_kg"] = (-2.5).into(),
                "model.spec.scales.modal_mass_kg = -2.5",
            ),
        ];
        for (edit, needle) in cases {
            let mut v = good.clone();
            edit(&mut v);
            let p = d.path().join("edited-model.json");
            std::fs::write(&p, serde_json::to_string_pretty(&v).unwrap()).unwrap();
            let e = SavedModel::read(&p).unwrap_err().to_string();
            assert!(
                e.contains("edited-model.json") && e.contains(needle),
                "{needle}: {e}"
            );
        }
    }

    /// Only a fit level that is not stationary is cut, at its resonance row, and only with
    /// `--rows settled`; a level that could not be checked keeps its rows.
    #[test]
    fn settled_rows_cut_only_unsettled_fit_levels() {
        let backbone = |resonance_row| LevelBackbone {
            file: "l.csv".into(),
            mean_force_n: 1.0,
            linear: backbone::LinearMode {
                frequency_hz: 80.0,
                damping_ratio: 1e-3,
                modal_mass_kg: 2.0,
                relative_rms: 0.0,
            },
            peak_amplitude_m: 1e-4,
            points: Vec::new(),
            point_rows: Vec::new(),
            side_points: Vec::new(),
            resonance_row,
            pointwise_modal_mass_kg: 2.0,
        };
        let sides = |stationary| SideComparison {
            file: "l.csv".into(),
            points_earlier: 5,
            points_later: 5,
            compared: 4,
            amplitude_range_m: (1e-4, 2e-4),
            damping_difference: if stationary {
                (-0.02, 0.01)
            } else {
                (-0.3, -0.1)
            },
            damping_form_interval: (-0.01, 0.0),
            differing: if stationary { 0 } else { 3 },
            differing_mean: if stationary { f64::NAN } else { -0.2 },
            noise_sd: (0.01, 0.02),
            damping_elasticity: (0.5, 1.5),
            frequency_difference_hz: (0.0, 0.1),
            frequency_reference: 0.0,
            frequency_reference_file: "l.csv".into(),
            frequency_shift: (-0.02, 0.03),
            frequency_noise_sd: (0.01, 0.02),
            frequency_differing: 0,
            frequency_differing_mean: f64::NAN,
            stationary,
        };
        let backbones = [backbone(20), backbone(21), backbone(22), backbone(23)];
        let checks = [
            Some(sides(true)),
            Some(sides(false)),
            None,
            Some(sides(false)),
        ];
        let fit = [0, 1, 2];
        assert_eq!(
            settled_first_rows(&fit, &checks, &backbones, FitRows::Settled),
            vec![None, Some(21), None]
        );
        assert_eq!(
            settled_first_rows(&fit, &checks, &backbones, FitRows::All),
            vec![None, None, None]
        );
    }

    /// Amplitudes print with five significant digits whatever their unit.
    #[test]
    fn significant_digits() {
        assert_eq!(significant(19.9), "19.900");
        assert_eq!(significant(138.91), "138.91");
        assert_eq!(significant(0.0123456), "0.012346");
        assert_eq!(significant(3.096e-8), "3.0960e-8");
    }
}
