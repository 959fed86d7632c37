//! `flaneur walk --csv`: the frames' figures written as each frame ends, so that a
//! walk of any length keeps none of them.

use std::path::{Path, PathBuf};

use anyhow::{Context, Result};

use flaneur::walk::review;

/// A walk's CSV, a row written as each frame ends.
pub(super) struct CsvRows {
    path: PathBuf,
    out: std::io::BufWriter<std::fs::File>,
}

impl CsvRows {
    /// Creates `path` and writes the header.
    pub(super) fn create(path: &Path) -> Result<CsvRows> {
        let file =
            std::fs::File::create(path).with_context(|| format!("creating {}", path.display()))?;
        let mut rows = CsvRows {
            path: path.to_path_buf(),
            out: std::io::BufWriter::new(file),
        };
        rows.line(review::FrameStats::CSV_HEADER)?;
        Ok(rows)
    }

    fn line(&mut self, text: &str) -> flaneur::Result<()> {
        use std::io::Write;
        writeln!(self.out, "{text}").map_err(|e| flaneur::Error::io(&self.path, e))
    }

    /// One frame's row.
    pub(super) fn write(&mut self, f: &review::FrameStats) -> flaneur::Result<()> {
        self.line(&f.csv_row())
    }

    /// Writes what is buffered.
    pub(super) fn finish(mut self) -> Result<()> {
        use std::io::Write;
        self.out
            .flush()
            .with_context(|| format!("writing {}", self.path.display()))
    }
}
