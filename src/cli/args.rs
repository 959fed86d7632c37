//! Values the commands parse from their arguments, and the settings derived from them
//! that several commands share.

/// `--speed` as the walk takes it: 0 for unpaced.
pub fn pace(speed: f32) -> Option<f32> {
    (speed != 0.0).then_some(speed)
}

/// A list argument's values, or `default` where none were given: an empty list stands
/// for the experiment's default, which the argument's help gives.
pub fn or_default<T>(given: Vec<T>, default: Vec<T>) -> Vec<T> {
    if given.is_empty() {
        default
    } else {
        given
    }
}

/// `--look`: heading and elevation in degrees, `yaw,pitch`.
pub fn parse_look(s: &str) -> std::result::Result<(f32, f32), String> {
    match s
        .split(',')
        .map(|p| p.trim().parse::<f32>())
        .collect::<Vec<_>>()[..]
    {
        [Ok(yaw), Ok(pitch)] if yaw.is_finite() && pitch.is_finite() => Ok((yaw, pitch)),
        _ => Err(format!(
            "{s:?} is not two finite numbers yaw,pitch (degrees)"
        )),
    }
}

/// `--size`: an image or window size, `WIDTHxHEIGHT` pixels.
pub fn parse_size(s: &str) -> std::result::Result<(u32, u32), String> {
    match s
        .split_once(['x', 'X'])
        .map(|(w, h)| (w.trim().parse(), h.trim().parse()))
    {
        Some((Ok(w), Ok(h))) if w > 0 && h > 0 => Ok((w, h)),
        _ => Err(format!(
            "{s:?} is not a size WIDTHxHEIGHT in pixels, like 960x540"
        )),
    }
}

/// A number that is finite: NaN and the infinities are refused where any number is
/// taken, so that none slips through a comparison meant to bound it.
pub fn finite_f32(s: &str) -> std::result::Result<f32, String> {
    match s.trim().parse::<f32>() {
        Ok(x) if x.is_finite() => Ok(x),
        Ok(x) => Err(format!("{x} is not a finite number")),
        Err(e) => Err(format!("{s:?} is not a number: {e}")),
    }
}

/// [`finite_f32`] for options kept in 64 bits.
pub fn finite_f64(s: &str) -> std::result::Result<f64, String> {
    match s.trim().parse::<f64>() {
        Ok(x) if x.is_finite() => Ok(x),
        Ok(x) => Err(format!("{x} is not a finite number")),
        Err(e) => Err(format!("{s:?} is not a number: {e}")),
    }
}

/// A field of view in degrees, within (0°, 180°); refused in degrees, as it is given.
pub fn parse_fov_degrees(s: &str) -> std::result::Result<f32, String> {
    match s.trim().parse::<f32>() {
        Ok(d) if d > 0.0 && d < 180.0 => Ok(d),
        Ok(d) => Err(format!(
            "a field of view of {d}°: give one within (0°, 180°)"
        )),
        Err(e) => Err(format!("{s:?} is not a number of degrees: {e}")),
    }
}

/// A point or a direction, `x,y,z`.
pub fn parse_vec3(s: &str) -> std::result::Result<glam::Vec3, String> {
    let v: Vec<f32> = s
        .split(',')
        .map(|p| p.trim().parse::<f32>())
        .collect::<std::result::Result<_, _>>()
        .map_err(|e| format!("{s:?}: {e}"))?;
    match v[..] {
        [x, y, z] if v.iter().all(|c| c.is_finite()) => Ok(glam::Vec3::new(x, y, z)),
        _ => Err(format!("{s:?} is not three finite numbers x,y,z")),
    }
}

/// The numbers an option takes: from `lo` to `hi`, each end in or out, in `unit`. A
/// number outside is refused at parse time with the range named, so that no absurd
/// value reaches a `Duration` (whose conversions panic past about 584 billion years) or
/// a threshold that would quietly select nothing.
struct Bounds {
    lo: f64,
    lo_in: bool,
    hi: f64,
    hi_in: bool,
    unit: &'static str,
    /// What the number is, for the refusal ("an idle timeout").
    what: &'static str,
}

impl Bounds {
    /// `x` if within, else the refusal, naming the number as it was `given`.
    fn check(&self, x: f64, given: &str) -> std::result::Result<f64, String> {
        let above = if self.lo_in {
            x >= self.lo
        } else {
            x > self.lo
        };
        let below = if self.hi_in {
            x <= self.hi
        } else {
            x < self.hi
        };
        if above && below {
            return Ok(x);
        }
        let (open, close) = (
            if self.lo_in { '[' } else { '(' },
            if self.hi_in { ']' } else { ')' },
        );
        let unit = if self.unit.is_empty() {
            String::new()
        } else {
            format!(" {}", self.unit)
        };
        Err(format!(
            "{} of {}{unit}: give one within {open}{}, {}{close}{unit}",
            self.what,
            given.trim(),
            self.lo,
            self.hi
        ))
    }

    /// The number `s` gives, if finite and within.
    fn parse(&self, s: &str) -> std::result::Result<f64, String> {
        self.check(finite_f64(s)?, s)
    }

    /// [`Bounds::parse`] for options kept in 32 bits: the number checked is the one kept.
    fn parse32(&self, s: &str) -> std::result::Result<f32, String> {
        let x = finite_f32(s)?;
        self.check(f64::from(x), s).map(|_| x)
    }

    /// A whole number of the option's unit, for options kept as integers.
    fn parse_whole(&self, s: &str) -> std::result::Result<u64, String> {
        let n: u64 = s
            .trim()
            .parse()
            .map_err(|e| format!("{s:?} is not a whole number of {}: {e}", self.unit))?;
        self.check(n as f64, s).map(|_| n)
    }
}

/// The longest a stream session may stay idle: a day.
const DAY_S: f64 = 86_400.0;

/// `serve-stream --idle-s`: an idle timeout, seconds within (0, a day].
pub fn idle_seconds(s: &str) -> std::result::Result<f64, String> {
    Bounds {
        lo: 0.0,
        lo_in: false,
        hi: DAY_S,
        hi_in: true,
        unit: "s",
        what: "an idle timeout",
    }
    .parse(s)
}

/// A wait before the server acts unasked (`--predict-after-ms`, `--idle-ms`):
/// milliseconds within [0, an hour].
pub fn wait_ms(s: &str) -> std::result::Result<u64, String> {
    Bounds {
        lo: 0.0,
        lo_in: true,
        hi: 3_600_000.0,
        hi_in: true,
        unit: "ms",
        what: "a wait",
    }
    .parse_whole(s)
}

/// A client's frame period (`--frame-ms`): milliseconds within (0, 10 000].
pub fn frame_ms(s: &str) -> std::result::Result<f64, String> {
    Bounds {
        lo: 0.0,
        lo_in: false,
        hi: 10_000.0,
        hi_in: true,
        unit: "ms",
        what: "a frame period",
    }
    .parse(s)
}

/// A link's round trip (`--rtt`, `--rtts`): milliseconds within [0, a minute].
pub fn round_trip_ms(s: &str) -> std::result::Result<u32, String> {
    Bounds {
        lo: 0.0,
        lo_in: true,
        hi: 60_000.0,
        hi_in: true,
        unit: "ms",
        what: "a round trip",
    }
    .parse_whole(s)
    .map(|n| n as u32)
}

/// A link's bandwidth (`--mbit`, `--mbits`): Mbit/s within [0.001, 1 000 000]; a
/// message's time on the link is its size over it.
pub fn bandwidth_mbit(s: &str) -> std::result::Result<f64, String> {
    Bounds {
        lo: 0.001,
        lo_in: true,
        hi: 1e6,
        hi_in: true,
        unit: "Mbit/s",
        what: "a bandwidth",
    }
    .parse(s)
}

/// A walk's frame rate (`--fps`), whose inverse is a path's time step: frames a
/// second within [0.1, 1000].
pub fn frame_rate(s: &str) -> std::result::Result<f32, String> {
    Bounds {
        lo: 0.1,
        lo_in: true,
        hi: 1000.0,
        hi_in: true,
        unit: "frames/s",
        what: "a frame rate",
    }
    .parse32(s)
}

/// A playback speed, times real time, that a path's times are divided by: 0
/// (unpaced) or within [0.01, 1000].
pub fn pace_factor(s: &str) -> std::result::Result<f32, String> {
    let x = finite_f32(s)?;
    if x == 0.0 {
        return Ok(0.0);
    }
    Bounds {
        lo: 0.01,
        lo_in: true,
        hi: 1000.0,
        hi_in: true,
        unit: "× real time",
        what: "a playback speed",
    }
    .check(f64::from(x), s)
    .map(|_| x)
    .map_err(|e| format!("{e}, or 0 for unpaced"))
}

/// A prefetch's look-ahead, seconds of motion (`--k`, `--ks`, `--next-cell-prefetch`):
/// at most a minute; a negative one turns prefetching off where the option says so.
pub fn seconds_ahead(s: &str) -> std::result::Result<f32, String> {
    let x = finite_f32(s)?;
    if x < 0.0 {
        return Ok(x);
    }
    Bounds {
        lo: 0.0,
        lo_in: true,
        hi: 60.0,
        hi_in: true,
        unit: "s",
        what: "a look-ahead",
    }
    .check(f64::from(x), s)
    .map(|_| x)
    .map_err(|e| format!("{e} (negative: no prefetching)"))
}

/// LOD selection's screen-space error τ (`--lod-tau`): a fraction of the viewport
/// within [0, 1), 0 for full detail.
pub fn lod_tau(s: &str) -> std::result::Result<f32, String> {
    Bounds {
        lo: 0.0,
        lo_in: true,
        hi: 1.0,
        hi_in: false,
        unit: "of the viewport",
        what: "a screen-space error τ",
    }
    .parse32(s)
    .map_err(|e| format!("{e} (0: full detail)"))
}

/// The rule that picks VISUAL's, VSC's and PB's internal LODs and levels
/// (`--selection`): `screen` (ours) or `thesis`.
pub fn selection(s: &str) -> std::result::Result<flaneur::hdov::Selection, String> {
    flaneur::hdov::Selection::from_name(s).map_err(|e| e.to_string())
}

/// A refinement's screen-space error τ (`--tau`, `--taus`): a fraction of the viewport
/// within (0, 1).
pub fn tau(s: &str) -> std::result::Result<f32, String> {
    Bounds {
        lo: 0.0,
        lo_in: false,
        hi: 1.0,
        hi_in: false,
        unit: "of the viewport",
        what: "a screen-space error τ",
    }
    .parse32(s)
}

/// A DoV threshold η (`--eta`, `--etas`): a degree of visibility, the share of the
/// view an object covers, within [0, 1].
pub fn eta(s: &str) -> std::result::Result<f32, String> {
    Bounds {
        lo: 0.0,
        lo_in: true,
        hi: 1.0,
        hi_in: true,
        unit: "of the view",
        what: "a DoV threshold η",
    }
    .parse32(s)
}

/// PBNP's and LANP's border regions (`--border`, `--borders`): a fraction of a cell's
/// side within (0, 0.5].
pub fn border(s: &str) -> std::result::Result<f64, String> {
    Bounds {
        lo: 0.0,
        lo_in: false,
        hi: 0.5,
        hi_in: true,
        unit: "of the cell's side",
        what: "a region border",
    }
    .parse(s)
}

/// `build --fill`: the share of each R-tree node bulk loading fills, within [0.1, 1].
pub fn fill(s: &str) -> std::result::Result<f32, String> {
    Bounds {
        lo: 0.1,
        lo_in: true,
        hi: 1.0,
        hi_in: true,
        unit: "of a node",
        what: "a fill factor",
    }
    .parse32(s)
}

/// `lod --ratio`: each level's triangles over the one before's, within (0, 1).
pub fn lod_ratio(s: &str) -> std::result::Result<f32, String> {
    Bounds {
        lo: 0.0,
        lo_in: false,
        hi: 1.0,
        hi_in: false,
        unit: "",
        what: "a level ratio",
    }
    .parse32(s)
}
