//! How long a reader's requests took, from sending one to its body's last byte: a
//! histogram (`hdrhistogram`, two significant digits, microseconds up to an hour) so
//! that a long walk's thousands of requests cost a few kilobytes, and the histograms of
//! many readers merge into one.

use std::time::Duration;

use hdrhistogram::Histogram;

/// The longest time recorded, microseconds; a longer one counts as this.
const MAX_MICROS: u64 = 3_600_000_000;

/// The times of a reader's requests.
///
/// ```
/// use std::time::Duration;
/// let mut t = flaneur::store::RequestTimes::default();
/// for ms in 1..=100 {
///     t.record(Duration::from_millis(ms));
/// }
/// assert_eq!(t.count(), 100);
/// assert!((t.quantile_ms(0.5) - 50.0).abs() < 1.0);
/// assert!((t.max_ms() - 100.0).abs() < 1.0);
/// ```
#[derive(Clone, Debug)]
pub struct RequestTimes {
    hist: Histogram<u64>,
}

impl Default for RequestTimes {
    fn default() -> RequestTimes {
        RequestTimes {
            // Bounds this wide with two digits are always accepted.
            hist: Histogram::new_with_bounds(1, MAX_MICROS, 2)
                .unwrap_or_else(|_| unreachable!("fixed, valid histogram bounds")),
        }
    }
}

impl RequestTimes {
    /// Counts one request that took `took`.
    pub fn record(&mut self, took: Duration) {
        let micros = (took.as_micros() as u64).clamp(1, MAX_MICROS);
        self.hist.saturating_record(micros);
    }

    /// Adds another reader's requests.
    pub fn merge(&mut self, other: &RequestTimes) {
        // Same bounds on both sides: the add cannot fail.
        let _ = self.hist.add(&other.hist);
    }

    /// Requests recorded.
    pub fn count(&self) -> u64 {
        self.hist.len()
    }

    /// The time under which a share `q` (0 to 1) of the requests finished, ms; 0 with none.
    pub fn quantile_ms(&self, q: f64) -> f64 {
        if self.hist.is_empty() {
            return 0.0;
        }
        self.hist.value_at_quantile(q.clamp(0.0, 1.0)) as f64 / 1e3
    }

    /// The longest request, ms; 0 with none.
    pub fn max_ms(&self) -> f64 {
        if self.hist.is_empty() {
            return 0.0;
        }
        self.hist.max() as f64 / 1e3
    }
}
