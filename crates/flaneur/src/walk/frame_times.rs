//! A walk's frame-time figures, as every mode's summary reports them: over frames 1
//! onwards, frame 0 (the cold load of the first cell) being the session's start rather
//! than the walk.

/// The mean, variance and longest of a walk's frame times, and those over 50 ms.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub(crate) struct FrameTimes {
    pub mean: f64,
    /// ms².
    pub variance: f64,
    pub max: f64,
    /// Frames over 50 ms, the thesis's real-time limit.
    pub over_50ms: usize,
}

/// [`frame_times`] a frame at a time, in constant memory: what a walk too long to keep
/// its frames uses. The mean is the same sum over the same count; the variance is
/// Welford's, equal to the two-pass one but for rounding.
#[derive(Clone, Copy, Debug, Default)]
pub(crate) struct FrameTimesTally {
    seen: usize,
    sum: f64,
    /// Welford's running mean and sum of squared deviations.
    mean: f64,
    m2: f64,
    max: f64,
    over_50ms: usize,
}

impl FrameTimesTally {
    /// The next frame's time (the first is left out, as [`frame_times`] leaves it).
    pub fn add(&mut self, ms: f64) {
        self.seen += 1;
        if self.seen == 1 {
            return;
        }
        let n = (self.seen - 1) as f64;
        self.sum += ms;
        let delta = ms - self.mean;
        self.mean += delta / n;
        self.m2 += delta * (ms - self.mean);
        self.max = self.max.max(ms);
        self.over_50ms += usize::from(ms > 50.0);
    }

    /// The figures so far.
    pub fn times(&self) -> FrameTimes {
        let n = self.seen.saturating_sub(1).max(1) as f64;
        FrameTimes {
            mean: self.sum / n,
            variance: self.m2 / n,
            max: self.max,
            over_50ms: self.over_50ms,
        }
    }
}

/// The figures of `ms`, every frame's time in order, frame 0 left out, in two passes:
/// what the tally is checked against.
#[cfg(test)]
pub(crate) fn frame_times(ms: &[f64]) -> FrameTimes {
    let walk = ms.get(1..).unwrap_or_default();
    let n = walk.len().max(1) as f64;
    let mean = walk.iter().sum::<f64>() / n;
    FrameTimes {
        mean,
        variance: walk.iter().map(|t| (t - mean).powi(2)).sum::<f64>() / n,
        max: walk.iter().copied().fold(0.0, f64::max),
        over_50ms: walk.iter().filter(|&&t| t > 50.0).count(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn frame_zero_is_left_out() {
        let t = frame_times(&[900.0, 10.0, 30.0, 60.0]);
        assert_eq!(t.mean, 100.0 / 3.0);
        assert_eq!((t.max, t.over_50ms), (60.0, 1));
        let m = 100.0 / 3.0;
        let v = ((10.0 - m) * (10.0 - m) + (30.0 - m) * (30.0 - m) + (60.0 - m) * (60.0 - m)) / 3.0;
        assert!((t.variance - v).abs() < 1e-9);
        assert_eq!(frame_times(&[5.0]), FrameTimes::default());
    }

    #[test]
    fn the_tally_agrees_with_the_two_passes() {
        let ms: Vec<f64> = (0..1000)
            .map(|i| 3.0 + ((i * 37) % 101) as f64 * 0.7)
            .collect();
        let mut tally = FrameTimesTally::default();
        for &t in &ms {
            tally.add(t);
        }
        let (a, b) = (tally.times(), frame_times(&ms));
        assert_eq!((a.mean, a.max, a.over_50ms), (b.mean, b.max, b.over_50ms));
        assert!(
            (a.variance - b.variance).abs() < 1e-9 * b.variance,
            "{a:?} {b:?}"
        );
        let mut one = FrameTimesTally::default();
        one.add(5.0);
        assert_eq!(one.times(), FrameTimes::default());
    }
}
