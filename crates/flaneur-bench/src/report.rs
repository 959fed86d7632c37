//! What every experiment's report gives the command that ran it: the rows as CSV, a
//! markdown summary that sets them beside the paper's figures, and the plots, under one
//! name. The command writes any report the same way (`NAME.csv`, `NAME.md`, the extra
//! CSVs and the plots in one folder) without knowing the experiment.

use std::path::Path;

use flaneur::error::Result;

/// An experiment's results, ready to be written beside the paper's figures.
pub trait Report {
    /// The stem of the report's files: its rows go to `NAME.csv`, its summary to
    /// `NAME.md`.
    fn name(&self) -> &'static str;

    /// The rows, as CSV with a header line.
    fn to_csv(&self) -> String;

    /// CSVs written beside `NAME.csv`: (file name, text). None by default.
    fn extra_csvs(&self) -> Vec<(&'static str, String)> {
        Vec::new()
    }

    /// The summary, markdown: the figures beside the paper's, and what they show.
    fn markdown(&self) -> String;

    /// Draws the report's plots as PNGs into `dir`, under the file names the
    /// experiment's module gives.
    fn plot(&self, dir: &Path) -> Result<()>;
}
