//! A building's base and top in metres from its tags: the base from `min_height`, else
//! `building:min_level` × the storey height, else the ground; the top from `height`,
//! else `building:levels` × the storey height, else the default above the base. Lengths are read as the
//! OpenStreetMap wiki writes them: metres bare or with `m`, feet with `ft` or `'`
//! (`'` and `"` for feet and inches), a decimal comma taken as a point.

use super::read::BuildingTags;
use super::report::{Repair, Skip};
use super::OsmOptions;

/// Metres per foot.
const FOOT: f64 = 0.3048;

/// A length tag in metres, or `None` when it is not one (or negative).
pub(super) fn parse_length(text: &str) -> Option<f64> {
    let t = text.trim().replace(',', ".");
    let t = t.as_str();
    let number = |s: &str| {
        s.trim()
            .parse::<f64>()
            .ok()
            .filter(|v| v.is_finite() && *v >= 0.0)
    };
    if let Some((feet, rest)) = t.split_once('\'') {
        let inches = rest.trim().trim_end_matches('"');
        let inches = if inches.is_empty() {
            0.0
        } else {
            number(inches)?
        };
        return Some((number(feet)? + inches / 12.0) * FOOT);
    }
    if let Some(feet) = t.strip_suffix("ft") {
        return Some(number(feet)? * FOOT);
    }
    number(t.strip_suffix('m').unwrap_or(t))
}

/// The base and top of a building in metres, with what was repaired on the way.
pub(super) fn base_and_top(
    tags: &BuildingTags,
    opts: &OsmOptions,
    repairs: &mut Vec<Repair>,
) -> Result<(f64, f64), Skip> {
    let storey = f64::from(opts.storey_height);
    let max = f64::from(opts.max_height);
    let mut tag = |value: &Option<String>, per: f64| -> Option<f64> {
        let v = value.as_deref()?;
        match parse_length(v).map(|x| x * per) {
            None => {
                repairs.push(Repair::UnreadableHeight);
                None
            }
            Some(x) if x > max => {
                repairs.push(Repair::AbsurdHeight);
                None
            }
            Some(x) => Some(x),
        }
    };
    let base = tag(&tags.min_height, 1.0)
        .or_else(|| tag(&tags.min_level, storey))
        .unwrap_or(0.0);
    // A part that floats (a bridge, a roof on columns) with no top of its own is the
    // default's height above its base.
    let top = tag(&tags.height, 1.0)
        .or_else(|| tag(&tags.levels, storey))
        .unwrap_or(base + f64::from(opts.default_height));
    if base >= top {
        return Err(Skip::BaseAboveTop);
    }
    Ok((base, top))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn lengths_are_read_in_the_wikis_forms() {
        for (text, m) in [
            ("12", 12.0),
            ("12.5 m", 12.5),
            ("7m", 7.0),
            ("3,5", 3.5),
            ("100 ft", 30.48),
            ("10'", 3.048),
            ("10'6\"", 3.2004),
        ] {
            let got = parse_length(text).unwrap();
            assert!((got - m).abs() < 1e-9, "{text}: {got}");
        }
        for bad in ["", "tall", "-3", "NaN", "inf", "12 storeys"] {
            assert_eq!(parse_length(bad), None, "{bad}");
        }
    }

    #[test]
    fn height_then_levels_then_default_and_bad_tags_are_counted() {
        let opts = OsmOptions::default();
        let storey = f64::from(opts.storey_height);
        let tags = |h: Option<&str>, l: Option<&str>, mh: Option<&str>| BuildingTags {
            height: h.map(String::from),
            levels: l.map(String::from),
            min_height: mh.map(String::from),
            ..BuildingTags::default()
        };
        let mut r = Vec::new();
        assert_eq!(
            base_and_top(&tags(Some("20"), Some("3"), None), &opts, &mut r),
            Ok((0.0, 20.0))
        );
        assert_eq!(
            base_and_top(&tags(None, Some("4"), None), &opts, &mut r),
            Ok((0.0, 4.0 * storey))
        );
        assert_eq!(
            base_and_top(&tags(None, None, None), &opts, &mut r),
            Ok((0.0, f64::from(opts.default_height)))
        );
        assert!(r.is_empty());
        assert_eq!(
            base_and_top(&tags(Some("tall"), Some("2"), None), &opts, &mut r),
            Ok((0.0, 2.0 * storey))
        );
        assert_eq!(r, vec![Repair::UnreadableHeight]);
        r.clear();
        assert_eq!(
            base_and_top(&tags(Some("90000"), None, None), &opts, &mut r)
                .unwrap()
                .1,
            f64::from(opts.default_height)
        );
        assert_eq!(r, vec![Repair::AbsurdHeight]);
        assert_eq!(
            base_and_top(&tags(Some("10"), None, Some("12")), &opts, &mut r),
            Err(Skip::BaseAboveTop)
        );
        assert_eq!(
            base_and_top(&tags(Some("10"), None, Some("4")), &opts, &mut r),
            Ok((4.0, 10.0))
        );
        let floating = base_and_top(&tags(None, None, Some("18")), &opts, &mut r);
        assert_eq!(floating, Ok((18.0, 18.0 + f64::from(opts.default_height))));
    }
}
