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

/// The figures of `ms`, every frame's time in order, frame 0 left out.
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
}
