//! `asperity elements`: preload map ⋈ calibration table → one row per contact element.

use asperity::calibrate::table::CalibrationTable;
use asperity::core::output::write_string_atomic;
use asperity::elements::{join, provenance_json, write_csv, InputFile};
use asperity::film::nodes::read_preloads_csv;
use asperity::{Error, Result};
use std::path::PathBuf;

/// Join node preloads (from `asperity film --nodes`) with a calibration table: kn, E0, Et scaled
/// by each element's area, k and mu at its local pressure; out-of-range elements flagged.
#[derive(clap::Args)]
pub struct ElementsArgs {
    /// Preload CSV (id,x_m,y_m,area_m2,pressure_Pa,N0_N).
    #[arg(long)]
    preload: PathBuf,
    /// Calibration table CSV (pressure_Pa,contact_area_ratio,kn_N_per_m3,...).
    #[arg(long)]
    table: PathBuf,
    /// Output element table CSV; a JSON provenance sidecar is written beside it (same stem).
    #[arg(long)]
    out: PathBuf,
}

pub fn run(args: ElementsArgs) -> Result<()> {
    let sidecar = args.out.with_extension("json");
    if sidecar == args.out {
        return Err(Error::param(
            "--out",
            format!(
                "the element table `{}` would be overwritten by its JSON sidecar (same name): \
                 give the table a .csv name",
                args.out.display()
            ),
        ));
    }
    // Neither the table nor its sidecar may be an input (the provenance record would hash a
    // file that no longer exists).
    let mut out = asperity::core::output::OutputSet::new();
    out.input(&args.preload, "--preload")?;
    out.input(&args.table, "--table")?;
    let table_staged = out.file(&args.out, "--out")?;
    let sidecar_staged = out.file(&sidecar, "the JSON sidecar of --out")?;
    let pre = read_preloads_csv(&args.preload)?;
    let table = CalibrationTable::read_csv(&args.table)?;
    let (rows, summary) = join(&pre, &table).map_err(|e| match e {
        Error::Data(m) => Error::Data(format!(
            "{} with {}: {m}",
            args.preload.display(),
            args.table.display()
        )),
        other => other,
    })?;
    let inputs = vec![
        InputFile::new("preload", &args.preload)?,
        InputFile::new("calibration_table", &args.table)?,
    ];
    let json = provenance_json(
        "elements",
        &inputs,
        serde_json::json!({ "output": args.out.display().to_string() }),
        serde_json::to_value(&summary).map_err(|e| Error::Data(e.to_string()))?,
    );
    write_csv(&table_staged, &rows)?;
    write_string_atomic(
        &sidecar_staged,
        &serde_json::to_string_pretty(&json).map_err(|e| Error::Data(e.to_string()))?,
    )?;
    out.commit()?;
    println!(
        "{} elements, total area {:.6e} m², total preload {:.6e} N; table range {:.4e}–{:.4e} Pa, element pressures {:.4e}–{:.4e} Pa",
        summary.n_elements,
        summary.total_area_m2,
        summary.total_load_n,
        summary.table_pressure_min_pa,
        summary.table_pressure_max_pa,
        summary.element_pressure_min_pa,
        summary.element_pressure_max_pa
    );
    if summary.n_below_range + summary.n_above_range > 0 {
        println!(
            "WARNING: {} elements below and {} above the calibration table's pressure range (values continued by the end rows' power law, flagged in out_of_range)",
            summary.n_below_range, summary.n_above_range
        );
    }
    for (ids, what) in [
        (
            &summary.not_converged_row_ids,
            "NOT converged in grid or patch size",
        ),
        (
            &summary.undetermined_row_ids,
            "of undetermined convergence (more realisations would tell)",
        ),
    ] {
        if !ids.is_empty() {
            println!(
                "WARNING: {} of {} elements take their values from calibration-table rows {what} (ids in the JSON sidecar; the verdicts per pressure are in the calibration's report)",
                ids.len(),
                summary.n_elements
            );
        }
    }
    if summary.n_open > 0 {
        println!(
            "WARNING: {} nodes of zero pressure (open contact, {:.4e} m²) left out of the table (open_ids in the JSON sidecar)",
            summary.n_open, summary.open_area_m2
        );
    }
    Ok(())
}
