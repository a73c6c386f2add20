//! Closing the loop: compare a model with measured hysteresis, find and add the missing effect.
use asperity::calibrate::table::CalibrationTable;
use asperity::core::error::require_positive;
use asperity::diagnose::report::{self, InputInfo, Outputs, Report};
use asperity::diagnose::{diagnose, Baseline, BaselineSource, Columns, Options, Record};
use asperity::{Error, Result};
use std::path::{Path, PathBuf};

/// Compare a Valanis element with a measured record (time, tangential displacement, tangential
/// force, optional normal force), find the missing effect on held-out cycles, and report the
/// errors before and after (text, JSON, CSV, PNG).
#[derive(clap::Args)]
pub struct DiagnoseArgs {
    /// Boxed: keeps the subcommand enum small.
    #[command(flatten)]
    pub args: Box<Flags>,
}

/// The flags of `asperity diagnose`.
#[derive(clap::Args)]
pub struct Flags {
    /// Measured record (CSV with a header row naming the columns).
    pub record: PathBuf,
    /// Time column (s).
    #[arg(long, default_value = "time_s")]
    pub time_column: String,
    /// Tangential displacement column (m).
    #[arg(long, default_value = "displacement_m")]
    pub displacement_column: String,
    /// Tangential force column (N).
    #[arg(long, default_value = "friction_force_N")]
    pub force_column: String,
    /// Normal force column (N), when the normal load was measured.
    #[arg(long)]
    pub normal_force_column: Option<String>,
    /// Relative acceleration across the joint (column in m/s²) instead of a displacement column:
    /// the displacement is its double integral in the frequency domain (said in the report).
    #[arg(long)]
    pub relative_acceleration_column: Option<String>,
    /// Acceleration of the mass whose inertia is the joint force (column in m/s²) instead of a
    /// force column: F = m·a with --mass-kg.
    #[arg(long, requires = "mass_kg")]
    pub inertia_acceleration_column: Option<String>,
    /// The mass (kg) of --inertia-acceleration-column.
    #[arg(
        long,
        requires = "inertia_acceleration_column",
        allow_hyphen_values = true
    )]
    pub mass_kg: Option<f64>,
    /// Calibration table (CSV, per unit area) giving the baseline element instead of fitting it.
    #[arg(long, requires_all = ["pressure_pa", "area_m2"])]
    pub table: Option<PathBuf>,
    /// Nominal contact pressure (Pa) at which the table is read.
    #[arg(long, requires = "table", allow_hyphen_values = true)]
    pub pressure_pa: Option<f64>,
    /// Nominal contact area (m²): per-area stiffnesses × area give the element's (N/m).
    #[arg(long, requires = "table", allow_hyphen_values = true)]
    pub area_m2: Option<f64>,
    /// Maximum number of effects to add (each must be supported by the held-out evidence).
    #[arg(long, default_value_t = 2)]
    pub max_effects: usize,
    /// Output directory: diagnose.{txt,json,csv}, diagnose-loops.png, diagnose-residual.png.
    #[arg(long, default_value = "diagnose-out")]
    pub out_dir: PathBuf,
}

/// Baseline element from a calibration table at pressure `p` (Pa) over area `a` (m²):
/// `E0 = E0''·a`, `Et = Et''·a` (N/m), `N = p·a` (N), `k`, `μ` as tabulated.
fn table_baseline(path: &Path, p: f64, a: f64) -> Result<(BaselineSource, String)> {
    require_positive("--pressure-pa", p)?;
    require_positive("--area-m2", a)?;
    asperity::core::limits::check_file_size(path, asperity::core::limits::MAX_TEXT_FILE_BYTES)?;
    let table = CalibrationTable::read_csv(path)?;
    let row = table.interpolate(p);
    let valanis = row.element.over_area(a).valanis()?;
    let mut source = format!(
        "from calibration table {} at {p:.4e} Pa over {a:.4e} m²",
        path.display()
    );
    if !row.in_range {
        let (lo, hi) = table.pressure_range();
        eprintln!(
            "warning: {p:.4e} Pa is outside the table's range [{lo:.4e}, {hi:.4e}] Pa; \
             the stiffnesses follow the end rows' power law, k and mu the end row"
        );
        source += " (outside the table's range: end rows' power law)";
    }
    Ok((
        BaselineSource::Given(Baseline {
            valanis,
            normal_n: p * a,
        }),
        source,
    ))
}

/// A table baseline whose slip force `μ·p·A` is not within a factor 100 of the measured force
/// amplitude cannot describe the record: `--pressure-pa` or `--area-m2` is wrong (e.g. an
/// area in mm² given as m²).
fn check_slip_force(baseline: &BaselineSource, record: &Record) -> Result<()> {
    let BaselineSource::Given(b) = baseline else {
        return Ok(());
    };
    let slip = b.valanis.mu * b.normal_n;
    let (lo, hi) = record
        .force_n
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, c), &f| {
            (a.min(f), c.max(f))
        });
    let amplitude = 0.5 * (hi - lo);
    let ratio = slip / amplitude;
    if !(ratio.is_finite() && (1e-2..=1e2).contains(&ratio)) {
        return Err(Error::param(
            "--pressure-pa / --area-m2",
            format!(
                "the table baseline's slip force μ·p·A = {} N is {} times the measured force \
                 amplitude {} N: check the pressure and the area (m²)",
                asperity::core::error::num(slip),
                asperity::core::error::num(ratio),
                asperity::core::error::num(amplitude)
            ),
        ));
    }
    Ok(())
}

pub fn run(args: DiagnoseArgs) -> Result<()> {
    let args = *args.args;
    // Refused now, before the analysis: an --out-dir that is a file or not writable.
    let mut out_set = asperity::core::output::OutputSet::in_dir(&args.out_dir, "--out-dir")?;
    out_set.writes(&Outputs::file_names())?;
    out_set.input(&args.record, "the measured record")?;
    out_set.inputs(&args.table, "--table")?;
    asperity::core::limits::check_count("--max-effects", args.max_effects, 8)?;
    let columns = Columns {
        time: args.time_column.clone(),
        displacement: args.displacement_column.clone(),
        force: args.force_column.clone(),
        normal_force: args.normal_force_column.clone(),
        ..Columns::default()
    }
    .with_accelerations(
        args.relative_acceleration_column.clone(),
        args.inertia_acceleration_column.clone(),
        args.mass_kg,
    )
    .map_err(|e| e.renamed_param("--mass-kg"))?;
    let record = Record::read_csv(&args.record, &columns)?;
    let (baseline, source) = match (&args.table, args.pressure_pa, args.area_m2) {
        (Some(table), Some(p), Some(a)) => {
            let b = table_baseline(table, p, a)?;
            check_slip_force(&b.0, &record)?;
            b
        }
        _ => (
            BaselineSource::Fitted,
            "fitted to the training cycles".to_string(),
        ),
    };
    let options = Options {
        baseline,
        max_effects: args.max_effects,
        ..Options::default()
    };
    let bar = super::spinner(&format!(
        "diagnosing {} ({} samples): fitting baseline and candidate effects",
        args.record.display(),
        record.len()
    ));
    let result = diagnose(&record, &options);
    bar.finish_and_clear();
    // Data errors of the analysis (no complete cycle, constant displacement, ...) name the file.
    let d = result.map_err(|e| match e {
        Error::Data(m) => Error::Data(format!("{}: {m}", args.record.display())),
        other => other,
    })?;
    let mut cols = vec![columns.time, columns.displacement, columns.force];
    cols.extend(columns.normal_force);
    let rep = Report::new(
        &d,
        InputInfo {
            file: args.record.display().to_string(),
            columns: cols,
            derived: record.derived.clone(),
            baseline_source: source,
        },
    );
    for (what, e) in [("before", &rep.errors_before), ("after", &rep.errors_after)] {
        for (name, v) in [
            ("normalised RMS error", e.nrms),
            ("peak force error", e.peak_force_error),
            ("energy-per-cycle error", e.energy_error),
        ] {
            asperity::core::sanity::finite_result(
                &format!("{}: the {name} {what}", args.record.display()),
                v,
            )?;
        }
    }
    // Every file is staged and appears at once (or not at all).
    report::write(&d, &rep, &Outputs::in_dir(&out_set.staging_dir()?))?;
    out_set.commit()?;
    let out = Outputs::in_dir(&args.out_dir);
    print!("{}", rep.text());
    println!(
        "\nwrote {}, {}, {}, {}, {}",
        out.text.display(),
        out.json.display(),
        out.csv.display(),
        out.loops_png.display(),
        out.residual_png.display()
    );
    Ok(())
}
