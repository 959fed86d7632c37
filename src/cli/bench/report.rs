//! Writing an experiment's report: the same files, named by the report, for every
//! experiment.

use std::path::{Path, PathBuf};

use anyhow::{Context, Result};

use crate::cli::write_file;
use flaneur_bench::report::Report;

/// Writes an experiment's report into `out` (its CSVs, markdown summary and plots), and
/// prints the summary.
pub fn write_report(out: &Path, r: &dyn Report) -> Result<()> {
    std::fs::create_dir_all(out).with_context(|| format!("creating {}", out.display()))?;
    let markdown = r.markdown();
    write_report_files(out, r, Some(&markdown))?;
    print!("{markdown}");
    println!("\nCSV, summary and plots in {}", out.display());
    Ok(())
}

/// Writes a report's CSVs, its summary when given, and its plots into `out`.
pub fn write_report_files(out: &Path, r: &dyn Report, markdown: Option<&str>) -> Result<()> {
    write_file(&report_file(out, r, "csv"), &r.to_csv())?;
    if let Some(md) = markdown {
        write_file(&report_file(out, r, "md"), md)?;
    }
    for (name, text) in r.extra_csvs() {
        write_file(&out.join(name), &text)?;
    }
    Ok(r.plot(out)?)
}

/// The report's file with extension `ext` in `out`.
pub fn report_file(out: &Path, r: &dyn Report, ext: &str) -> PathBuf {
    out.join(format!("{}.{ext}", r.name()))
}
