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
