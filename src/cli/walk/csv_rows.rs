//! `flaneur walk --csv`: the frames' figures written as each frame ends, so that a
//! walk of any length keeps none of them.

use std::path::{Path, PathBuf};

use anyhow::{Context, Result};

/// A walk's CSV, a row written as each frame ends.
pub(super) struct CsvRows {
    path: PathBuf,
    out: std::io::BufWriter<std::fs::File>,
}

impl CsvRows {
    /// Creates `path` and writes `header`.
    pub(super) fn create(path: &Path, header: &str) -> Result<CsvRows> {
        let file =
            std::fs::File::create(path).with_context(|| format!("creating {}", path.display()))?;
        let mut rows = CsvRows {
            path: path.to_path_buf(),
            out: std::io::BufWriter::new(file),
        };
        rows.write(header)?;
        Ok(rows)
    }

    /// One row (no line end).
    pub(super) fn write(&mut self, row: &str) -> flaneur::Result<()> {
        use std::io::Write;
        writeln!(self.out, "{row}").map_err(|e| flaneur::Error::io(&self.path, e))
    }

    /// Writes what is buffered.
    pub(super) fn finish(mut self) -> Result<()> {
        use std::io::Write;
        self.out
            .flush()
            .with_context(|| format!("writing {}", self.path.display()))
    }
}

/// Writes the row `row` makes into `rows`, when the walk writes a CSV.
pub(super) fn write_row(
    rows: &mut Option<CsvRows>,
    row: impl FnOnce() -> String,
) -> flaneur::Result<()> {
    match rows.as_mut() {
        Some(rows) => rows.write(&row()),
        None => Ok(()),
    }
}
