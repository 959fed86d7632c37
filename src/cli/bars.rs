//! Progress bars on standard error, drawn from the engine's progress reports (the engine
//! never draws them itself).

use std::collections::HashMap;
use std::sync::Mutex;

use anyhow::Result;
use flaneur::progress::{Progress, Step};
use indicatif::{ProgressBar, ProgressStyle};

/// One bar per step of a long job, made when the step first reports.
#[derive(Default)]
pub struct Bars {
    bars: Mutex<HashMap<Step, ProgressBar>>,
}

impl Progress for Bars {
    fn update(&self, step: Step, done: u64, total: Option<u64>) {
        let mut bars = self.bars.lock().unwrap_or_else(|e| e.into_inner());
        let bar = bars.entry(step).or_insert_with(|| {
            let bar = ProgressBar::new(total.unwrap_or(0));
            let template = format!(
                "{} {{bar:40}} {{pos}}/{{len}} {} ({{per_sec}}, eta {{eta}})",
                step.name(),
                step.unit()
            );
            bar.set_style(
                ProgressStyle::with_template(&template)
                    .unwrap_or_else(|_| ProgressStyle::default_bar()),
            );
            bar
        });
        if let Some(total) = total {
            bar.set_length(total);
        }
        bar.set_position(done);
    }

    fn finish(&self, step: Step) {
        let bars = self.bars.lock().unwrap_or_else(|e| e.into_inner());
        if let Some(bar) = bars.get(&step) {
            bar.finish_and_clear();
        }
    }
}

/// Runs `f` under a progress bar that its `progress(done, total)` moves.
pub fn with_bar<T>(
    what: &str,
    f: impl FnOnce(&mut dyn FnMut(usize, usize)) -> flaneur::Result<T>,
) -> Result<T> {
    let bar = indicatif::ProgressBar::new(1);
    bar.set_message(what.to_string());
    bar.set_style(
        indicatif::ProgressStyle::with_template("{msg}: [{bar:30}] {pos}/{len} ({elapsed})")
            .expect("a valid template")
            .progress_chars("=> "),
    );
    let result = f(&mut |done, total| {
        bar.set_length(total as u64);
        bar.set_position(done as u64);
    });
    bar.finish_and_clear();
    Ok(result?)
}

/// The bar of a city's objects as the generator writes them (as `citygen` draws it).
pub fn city_bar(objects: u64) -> ProgressBar {
    let bar = ProgressBar::new(objects);
    bar.set_style(
        ProgressStyle::with_template(
            "{elapsed_precise} [{wide_bar}] {pos}/{len} objects ({per_sec}, {eta} left)",
        )
        .unwrap_or_else(|_| ProgressStyle::default_bar())
        .progress_chars("=> "),
    );
    bar
}
