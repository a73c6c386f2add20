//! Calibration configuration (TOML), with the built-in reference case.
//!
//! Every section refuses unknown keys; every value is checked and an invalid one is reported
//! with its dotted key (`loading.pressures_pa`, `fit.k_starts`, ...) and, when read from a file,
//! the file and line. SI units throughout; key names carry the unit.
//!
//! ```toml
//! [surface]                 # Gaussian-correlated rough patch (crate::surface::generate)
//! rq_m = 1.77e-7            # rms height
//! clx_m = 6.6e-6            # 1/e correlation lengths
//! cly_m = 6.6e-6
//! lx_m = 2.5e-4             # patch size (one period)
//! ly_m = 2.5e-4
//! nx = 1024                 # grid points
//! ny = 1024
//! seed = 1                  # seed of the first realisation
//!
//! [realisations]
//! count = 8                 # surfaces of these statistics, seeds seed, seed + 1, ...
//!
//! [material]                # both bodies (quasi-identical: normal/tangential decouple)
//! youngs_modulus_pa = 2.1e11
//! poisson_ratio = 0.3
//! # hardness_pa = 3.33e9    # optional: elastic–perfectly plastic contact, p ≤ H (Pa, or a
//! #                         # grade name such as "steel-42crmo4"); kn is then the
//! #                         # unloading/reloading stiffness about the plastic state
//!
//! [contact]
//! mu = 0.6                  # friction coefficient: BEM slip limit, held fixed in the fit
//! normal_tolerance = 1e-10  # normal contact relative gap error
//! tangential_tolerance = 1e-4
//!
//! [loading]
//! pressures_pa = [1e5, 2e5, 1e6, 2e6, 5e6, 1e7]   # positive, strictly increasing
//! amplitude_factors = [0.2, 0.4, 0.7, 1.0, 1.5]   # δa / gross-slip displacement, increasing
//! steps_per_cycle = 40      # BEM steps per cycle (multiple of 4)
//!
//! [fit]
//! fit_et = false            # also fit the residual stiffness Et (else Et = 0)
//! k_starts = [0.1, 0.5, 0.9]  # Nelder–Mead starts for k, each in [0, 1)
//! max_iterations = 600      # per start
//!
//! [convergence]             # verdicts of the grid and patch-size checks
//! relative_tolerance = 0.05 # kn and E0: change allowed, relative to the mean
//! k_tolerance = 0.05        # k: change allowed (absolute)
//! ```

use crate::core::error::{Error, Result};
use crate::surface::generate::GaussianSurfaceSpec;
use std::path::Path;

/// Elastic material of both bodies.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(deny_unknown_fields)]
pub struct MaterialConfig {
    /// Young's modulus (Pa).
    pub youngs_modulus_pa: f64,
    /// Poisson's ratio (-).
    pub poisson_ratio: f64,
    /// Indentation hardness H (Pa, or a grade of [`crate::core::material::MATERIAL_GRADES`] by
    /// name): the contact pressure is bounded by it (hardness-limited normal contact,
    /// [`crate::contact::normal`]), the tangential loops run on that bounded pressure and the
    /// table's kn is the unloading/reloading stiffness about the plastically deformed state.
    /// Absent: elastic contact.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub hardness_pa: Option<crate::core::material::Hardness>,
}

impl MaterialConfig {
    /// The hardness in Pa (`None`: elastic contact), checked; errors name `material.hardness_pa`.
    pub fn hardness(&self) -> Result<Option<f64>> {
        self.hardness_pa
            .as_ref()
            .map(|h| h.pa("material.hardness_pa"))
            .transpose()
    }
}

/// Friction and solver tolerances.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ContactConfig {
    /// Coulomb friction coefficient μ (-), used by the BEM and held fixed in the fit.
    pub mu: f64,
    /// Tolerance of the normal solver (relative gap error).
    pub normal_tolerance: f64,
    /// Tolerance of the tangential solver (relative natural residual).
    pub tangential_tolerance: f64,
}

/// Pressures and the tangential history at each.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(deny_unknown_fields)]
pub struct LoadingConfig {
    /// Nominal pressures (Pa), positive and strictly increasing.
    pub pressures_pa: Vec<f64>,
    /// Displacement amplitudes as multiples of the gross-slip displacement at each pressure,
    /// positive and strictly increasing (from microslip to gross slip).
    pub amplitude_factors: Vec<f64>,
    /// BEM load steps per cycle (multiple of 4, ≥ 8).
    pub steps_per_cycle: usize,
}

/// How many random surfaces of the configured statistics.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RealisationsConfig {
    /// Number of realisations (seeds `surface.seed`, `surface.seed + 1`, ...), ≥ 1.
    pub count: usize,
}

/// Tolerances of the grid and patch-size convergence verdicts (`calibrate::convergence`).
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ConvergenceConfig {
    /// Allowed change of kn and E0, relative to their mean (-).
    pub relative_tolerance: f64,
    /// Allowed change of k (absolute, -).
    pub k_tolerance: f64,
}

/// Fit settings.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(deny_unknown_fields)]
pub struct FitConfig {
    /// Fit the residual stiffness Et too.
    pub fit_et: bool,
    /// Starting values of k for the Nelder–Mead starts, each in [0, 1).
    pub k_starts: Vec<f64>,
    /// Nelder–Mead iteration cap per start.
    pub max_iterations: u64,
}

/// A whole calibration run.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(deny_unknown_fields)]
pub struct CalibrationConfig {
    /// `[surface]`: statistics, patch size, grid and first seed of the Gaussian surfaces.
    pub surface: GaussianSurfaceSpec,
    /// `[realisations]`: how many surfaces.
    pub realisations: RealisationsConfig,
    /// `[material]`: elastic constants of the bodies.
    pub material: MaterialConfig,
    /// `[contact]`: friction coefficient and solver tolerances.
    pub contact: ContactConfig,
    /// `[loading]`: pressures, amplitudes and load steps.
    pub loading: LoadingConfig,
    /// `[fit]`: the Valanis fit's settings.
    pub fit: FitConfig,
    /// `[convergence]`: tolerances of the grid and patch-size verdicts.
    pub convergence: ConvergenceConfig,
}

impl CalibrationConfig {
    /// The built-in reference case: Rq 0.177 µm, cl 6.6 µm, 250 µm patch, 1024², 8
    /// realisations (seeds 1–8), steel on steel (E = 210 GPa, ν = 0.3), μ = 0.6, pressures 0.1,
    /// 0.2, 1, 2, 5, 10 MPa, amplitudes 0.2, 0.4, 0.7, 1 and 1.5 × the gross-slip displacement.
    /// `calib/reference.toml` is this configuration written out.
    pub fn reference() -> Self {
        Self {
            surface: GaussianSurfaceSpec::reference(),
            realisations: RealisationsConfig { count: 8 },
            material: MaterialConfig {
                youngs_modulus_pa: 210e9,
                poisson_ratio: 0.3,
                hardness_pa: None,
            },
            contact: ContactConfig {
                mu: 0.6,
                normal_tolerance: 1e-10,
                tangential_tolerance: 1e-4,
            },
            loading: LoadingConfig {
                pressures_pa: vec![0.1e6, 0.2e6, 1e6, 2e6, 5e6, 10e6],
                amplitude_factors: vec![0.2, 0.4, 0.7, 1.0, 1.5],
                steps_per_cycle: 40,
            },
            fit: FitConfig {
                fit_et: false,
                k_starts: vec![0.1, 0.5, 0.9],
                max_iterations: 600,
            },
            convergence: ConvergenceConfig {
                relative_tolerance: 0.05,
                k_tolerance: 0.05,
            },
        }
    }

    /// Parse TOML text and validate (texts above [`crate::core::limits::MAX_TEXT_FILE_BYTES`] are
    /// refused by [`Self::read`] before they are read). Errors carry the dotted key and, via [`Self::read`], the
    /// file and line.
    pub fn from_toml_str(text: &str) -> Result<Self> {
        Self::parse(text, Path::new("<config>"))
    }

    /// Read and validate a TOML configuration file.
    pub fn read(path: &Path) -> Result<Self> {
        crate::core::limits::check_file_size(path, crate::core::limits::MAX_TEXT_FILE_BYTES)?;
        let text = std::fs::read_to_string(path).map_err(|e| Error::io(path, e))?;
        Self::parse(&text, path)
    }

    fn parse(text: &str, path: &Path) -> Result<Self> {
        let cfg: Self =
            toml::from_str(text).map_err(|e| crate::core::input::toml_error(path, text, e))?;
        cfg.validate().map_err(|e| match e {
            Error::InvalidParameter { name, message } => {
                let line = key_line(text, &name);
                Error::parse(path, line, format!("invalid `{name}`: {message}"))
            }
            Error::Limit { name, message } => {
                let line = key_line(text, &name);
                Error::parse(path, line, format!("`{name}`: resource limit: {message}"))
            }
            other => other,
        })?;
        Ok(cfg)
    }

    /// TOML text of this configuration (what the sidecar records and `calib/reference.toml`
    /// holds).
    pub fn to_toml_string(&self) -> Result<String> {
        toml::to_string(self).map_err(|e| Error::Data(format!("cannot serialise config: {e}")))
    }

    /// Check every value; the error names the dotted key.
    pub fn validate(&self) -> Result<()> {
        let prefixed = |section: &'static str| {
            move |e: Error| match e {
                Error::InvalidParameter { name, message } => {
                    Error::param(format!("{section}.{name}"), message)
                }
                other => other,
            }
        };
        self.surface.validate().map_err(prefixed("surface"))?;
        crate::core::material::Material {
            youngs_modulus_pa: self.material.youngs_modulus_pa,
            poisson_ratio: self.material.poisson_ratio,
        }
        .validated("material")?;
        let hardness = self.material.hardness()?;
        let c = &self.contact;
        crate::core::sanity::friction_coefficient("contact.mu", c.mu)?;
        crate::core::sanity::tolerance("contact.normal_tolerance", c.normal_tolerance)?;
        crate::core::sanity::tolerance("contact.tangential_tolerance", c.tangential_tolerance)?;
        // Resource limits (before anything is allocated) and pressures the model resolves.
        let s = &self.surface;
        crate::core::limits::check_grid(
            "surface.nx",
            s.nx,
            s.ny,
            crate::core::limits::CONTACT_BYTES_PER_POINT,
        )?;
        let l = &self.loading;
        if l.pressures_pa.is_empty() {
            return Err(Error::param("loading.pressures_pa", "no pressure given"));
        }
        for (i, &p) in l.pressures_pa.iter().enumerate() {
            if !(p.is_finite() && p > 0.0) {
                return Err(Error::param(
                    "loading.pressures_pa",
                    format!("entry {i} must be finite and > 0, got {p}"),
                ));
            }
            if i > 0 && p <= l.pressures_pa[i - 1] {
                return Err(Error::param(
                    "loading.pressures_pa",
                    format!(
                        "must be strictly increasing: entry {i} ({p}) follows {}",
                        l.pressures_pa[i - 1]
                    ),
                ));
            }
        }
        if let (Some(h), Some(&p)) = (hardness, l.pressures_pa.last()) {
            if p >= h {
                return Err(Error::param(
                    "material.hardness_pa",
                    format!(
                        "H = {h:e} Pa must exceed the highest nominal pressure {p:e} Pa (a \
                         contact at p̄ ≥ H is plastic over the whole patch)"
                    ),
                ));
            }
        }
        crate::core::limits::check_count(
            "loading.pressures_pa",
            l.pressures_pa.len(),
            crate::core::limits::MAX_PRESSURES,
        )?;
        let material = crate::core::material::Material {
            youngs_modulus_pa: self.material.youngs_modulus_pa,
            poisson_ratio: self.material.poisson_ratio,
        };
        let e_star = crate::core::material::composite_modulus(material, material)?;
        crate::core::sanity::contact_pressures_for(
            "loading.pressures_pa",
            &l.pressures_pa,
            e_star,
            s.lx_m.max(s.ly_m),
            8.0 * s.rq_m,
        )?;
        crate::core::limits::check_count(
            "loading.steps_per_cycle",
            l.steps_per_cycle,
            crate::core::limits::MAX_STEPS_PER_CYCLE,
        )?;
        crate::calibrate::amplitudes::check_factors(&l.amplitude_factors).map_err(|e| match e {
            Error::InvalidParameter { message, .. } => {
                Error::param("loading.amplitude_factors", message)
            }
            other => other,
        })?;
        if self.realisations.count == 0 {
            return Err(Error::param("realisations.count", "must be at least 1"));
        }
        let c = &self.convergence;
        crate::core::error::require_positive(
            "convergence.relative_tolerance",
            c.relative_tolerance,
        )?;
        crate::core::error::require_positive("convergence.k_tolerance", c.k_tolerance)?;
        crate::core::limits::check_count("realisations.count", self.realisations.count, 1000)?;
        if l.steps_per_cycle < 8 || !l.steps_per_cycle.is_multiple_of(4) {
            return Err(Error::param(
                "loading.steps_per_cycle",
                format!(
                    "must be a multiple of 4 and at least 8 (reversals on samples), got {}",
                    l.steps_per_cycle
                ),
            ));
        }
        let f = &self.fit;
        if f.k_starts.is_empty() {
            return Err(Error::param("fit.k_starts", "give at least one start"));
        }
        if let Some(k) = f
            .k_starts
            .iter()
            .find(|k| !(k.is_finite() && (0.0..1.0).contains(*k)))
        {
            return Err(Error::param(
                "fit.k_starts",
                format!("each k must satisfy 0 <= k < 1, got {k}"),
            ));
        }
        if f.max_iterations == 0 {
            return Err(Error::param("fit.max_iterations", "must be at least 1"));
        }
        crate::core::limits::check_count("fit.k_starts", f.k_starts.len(), 100)?;
        crate::core::limits::check_count(
            "fit.max_iterations",
            f.max_iterations as usize,
            1_000_000,
        )?;
        Ok(())
    }
}

/// 1-based line of `section.key = ...` in TOML text (0 if not found, e.g. for a built-in value).
fn key_line(text: &str, dotted: &str) -> usize {
    let (section, key) = match dotted.split_once('.') {
        Some((s, k)) => (Some(s), k),
        None => (None, dotted),
    };
    let mut current: Option<String> = None;
    for (i, raw) in text.lines().enumerate() {
        let line = raw.split('#').next().unwrap_or("").trim();
        if let Some(h) = line.strip_prefix('[').and_then(|l| l.strip_suffix(']')) {
            current = Some(h.trim().to_string());
            continue;
        }
        let in_section = match section {
            Some(s) => current.as_deref() == Some(s),
            None => current.is_none(),
        };
        if in_section {
            if let Some((k, _)) = line.split_once('=') {
                if k.trim() == key {
                    return i + 1;
                }
            }
        }
    }
    0
}

#[cfg(test)]
mod tests {
    use super::*;

    fn reference_text() -> String {
        CalibrationConfig::reference().to_toml_string().unwrap()
    }

    #[test]
    fn calib_reference_toml_is_the_built_in_case() {
        let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("calib/reference.toml");
        assert_eq!(
            CalibrationConfig::read(&path).unwrap(),
            CalibrationConfig::reference()
        );
    }

    #[test]
    fn reference_round_trips_through_toml() {
        let cfg = CalibrationConfig::from_toml_str(&reference_text()).unwrap();
        assert_eq!(cfg, CalibrationConfig::reference());
    }

    fn refused(text: &str) -> String {
        CalibrationConfig::from_toml_str(text)
            .unwrap_err()
            .to_string()
    }

    #[test]
    fn invalid_values_are_refused_naming_the_key_and_line() {
        let base = reference_text();
        let with = |from: &str, to: &str| {
            assert!(base.contains(from), "{from}");
            base.replace(from, to)
        };
        let msg = refused(&with("mu = 0.6", "mu = -0.6"));
        assert!(msg.contains("contact.mu"), "{msg}");
        let msg = refused(&with("k_starts = [0.1, 0.5, 0.9]", "k_starts = [0.1, 1.0]"));
        assert!(
            msg.contains("fit.k_starts") && msg.contains("0 <= k < 1"),
            "{msg}"
        );
        let msg = refused(&with("k_starts = [0.1, 0.5, 0.9]", "k_starts = [-0.2]"));
        assert!(msg.contains("fit.k_starts"), "{msg}");
        let msg = refused(&with(
            "pressures_pa = [100000.0, 200000.0",
            "pressures_pa = [200000.0, 100000.0",
        ));
        assert!(
            msg.contains("loading.pressures_pa") && msg.contains("increasing"),
            "{msg}"
        );
        let msg = refused(&with("pressures_pa = [100000.0", "pressures_pa = [0.0"));
        assert!(
            msg.contains("loading.pressures_pa") && msg.contains("> 0"),
            "{msg}"
        );
        let msg = refused(&with("rq_m = ", "rq_m = -"));
        assert!(msg.contains("surface.rq_m"), "{msg}");
        // The line of the offending key is reported.
        let text = with("mu = 0.6", "mu = -0.6");
        let line = text.lines().position(|l| l.starts_with("mu =")).unwrap() + 1;
        assert!(
            refused(&text).contains(&format!(":{line}:")),
            "{}",
            refused(&text)
        );
    }

    #[test]
    fn unknown_keys_and_missing_keys_are_refused() {
        let base = reference_text();
        let msg = refused(&base.replace("[fit]\n", "[fit]\nk_start = 0.5\n"));
        assert!(msg.contains("k_start"), "{msg}");
        let msg = refused(&format!("{base}\n[extra]\nx = 1\n"));
        assert!(msg.contains("extra"), "{msg}");
        let msg = refused(&base.replace("fit_et = false\n", ""));
        assert!(msg.contains("fit_et"), "{msg}");
        let msg = refused(&base.replace("count = 8", "count = 0"));
        assert!(msg.contains("realisations.count"), "{msg}");
        let msg = refused(&base.replace(
            "amplitude_factors = [0.2, 0.4, 0.7, 1.0, 1.5]",
            "amplitude_factors = [0.4, 0.2]",
        ));
        assert!(msg.contains("loading.amplitude_factors"), "{msg}");
    }

    /// `material.hardness_pa`: absent means elastic (the reference file has none); a number in
    /// Pa or a grade name; an unknown name, a non-positive value or one not above the highest
    /// nominal pressure is refused naming the key.
    #[test]
    fn hardness_is_a_value_or_a_grade_name() {
        let base = reference_text();
        assert!(!base.contains("hardness_pa"));
        assert_eq!(
            CalibrationConfig::reference().material.hardness().unwrap(),
            None
        );
        let with = |v: &str| {
            base.replace(
                "poisson_ratio = 0.3\n",
                &format!("poisson_ratio = 0.3\nhardness_pa = {v}\n"),
            )
        };
        let cfg = CalibrationConfig::from_toml_str(&with("3.0e9")).unwrap();
        assert_eq!(cfg.material.hardness().unwrap(), Some(3.0e9));
        let cfg = CalibrationConfig::from_toml_str(&with("\"inconel-718\"")).unwrap();
        let h = crate::core::material::material_grade("inconel-718")
            .unwrap()
            .hardness_pa();
        assert_eq!(cfg.material.hardness().unwrap(), Some(h));
        // The canonical TOML keeps it.
        let again = CalibrationConfig::from_toml_str(&cfg.to_toml_string().unwrap()).unwrap();
        assert_eq!(again, cfg);
        for (v, what) in [
            ("\"brass\"", "steel-42crmo4"),
            ("-1e9", "> 0"),
            ("5e6", "exceed"),
        ] {
            let msg = refused(&with(v));
            assert!(
                msg.contains("material.hardness_pa") && msg.contains(what),
                "{v}: {msg}"
            );
        }
    }
}
