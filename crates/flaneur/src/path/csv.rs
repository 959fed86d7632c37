//! The camera-path file: plain CSV, one pose per line, so that a recorded session (the
//! thesis replays one recorded session on every configuration, Shou 2002 §4.4.2) can be
//! written by any tool and read back exactly.
//!
//! ```text
//! time,x,y,z,yaw,pitch
//! 0,1000,1.7,1000,1.5707964,0.012
//! 0.03333333333333333,1000,1.7,1000.5,1.5707964,0.0121
//! ```
//!
//! - The first line is the header, exactly these six names (case and spaces aside).
//! - `time` is seconds (f64), strictly increasing; `x, y, z` metres, `yaw, pitch`
//!   radians (f32), with the conventions of [`Camera`](crate::geom::Camera). Every value
//!   is finite and `|pitch| < π/2`.
//! - Blank lines are ignored; at least one pose is required.
//! - Numbers are written in the shortest form that reads back to the same float, so a
//!   path survives a save and load bit for bit.
//!
//! A bad line is an error that names the file and the line number (1-based).

use std::fmt::Write as _;
use std::path::Path;

use glam::Vec3;

use super::{check_pose, CameraPath, Pose};
use crate::error::{Error, Result};

/// The header line of a camera-path file.
const HEADER: &str = "time,x,y,z,yaw,pitch";

impl CameraPath {
    /// Writes the path as CSV: the header line `time,x,y,z,yaw,pitch`, then one pose a
    /// line, `time` in seconds, `x, y, z` in metres, `yaw, pitch` in radians (as
    /// [`Camera`](crate::geom::Camera)'s), each number in the shortest form that reads
    /// back to the same float, so that a path survives a save and load bit for bit.
    /// Errors on an invalid path (one that [`CameraPath::load_csv`] would refuse, the
    /// empty path included) or on I/O.
    ///
    /// ```text
    /// time,x,y,z,yaw,pitch
    /// 0,1000,1.7,1000,1.5707964,0.012
    /// 0.03333333333333333,1000,1.7,1000.5,1.5707964,0.0121
    /// ```
    pub fn save_csv(&self, path: impl AsRef<Path>) -> Result<()> {
        let path = path.as_ref();
        self.validate()?;
        std::fs::write(path, self.to_csv()).map_err(|e| Error::io(path, e))
    }

    /// Reads a path written by [`CameraPath::save_csv`] or by hand: the header (case and
    /// spaces aside), then at least one pose; blank lines are ignored. Every value must
    /// be finite, `|pitch| < π/2`, and times strictly increasing. A bad line is an error
    /// that names the file and the line (counted from 1).
    pub fn load_csv(path: impl AsRef<Path>) -> Result<CameraPath> {
        let path = path.as_ref();
        let text = std::fs::read_to_string(path).map_err(|e| Error::io(path, e))?;
        parse(&text).map_err(|(line, what)| Error::BadInput {
            path: path.into(),
            what: format!("line {line}: {what}"),
        })
    }

    /// The CSV text of the path, header included.
    pub fn to_csv(&self) -> String {
        let mut out = String::with_capacity(32 + self.poses.len() * 64);
        out.push_str(HEADER);
        out.push('\n');
        for p in &self.poses {
            // `{}` on floats prints the shortest decimal that parses back to the same value.
            let _ = writeln!(
                out,
                "{},{},{},{},{},{}",
                p.time, p.position.x, p.position.y, p.position.z, p.yaw, p.pitch
            );
        }
        out
    }
}

/// Parses CSV text; an error is (line number, what is wrong).
fn parse(text: &str) -> std::result::Result<CameraPath, (usize, String)> {
    let mut lines = text.lines().enumerate().map(|(i, l)| (i + 1, l));
    let header = lines
        .next()
        .map(|(_, l)| l.trim_start_matches('\u{feff}'))
        .unwrap_or("");
    let squeezed: String = header.chars().filter(|c| !c.is_whitespace()).collect();
    if !squeezed.eq_ignore_ascii_case(HEADER) {
        return Err((
            1,
            format!("expected the header '{HEADER}', found '{header}'"),
        ));
    }
    let mut poses: Vec<Pose> = Vec::new();
    for (n, line) in lines {
        if line.trim().is_empty() {
            continue;
        }
        let fields: Vec<&str> = line.split(',').map(str::trim).collect();
        if fields.len() != 6 {
            return Err((
                n,
                format!(
                    "expected 6 comma-separated values ({HEADER}), found {}",
                    fields.len()
                ),
            ));
        }
        let bad = |k: usize| {
            (
                n,
                format!(
                    "{} '{}' is not a number",
                    HEADER.split(',').nth(k).unwrap_or("value"),
                    fields[k]
                ),
            )
        };
        let time: f64 = fields[0].parse().map_err(|_| bad(0))?;
        let mut v = [0f32; 5];
        for (k, slot) in v.iter_mut().enumerate() {
            *slot = fields[k + 1].parse().map_err(|_| bad(k + 1))?;
        }
        let pose = Pose {
            time,
            position: Vec3::new(v[0], v[1], v[2]),
            yaw: v[3],
            pitch: v[4],
        };
        check_pose(&pose, poses.last().map(|p| p.time)).map_err(|what| (n, what))?;
        poses.push(pose);
    }
    if poses.is_empty() {
        return Err((1, "no poses after the header".into()));
    }
    Ok(CameraPath { poses })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn err(text: &str) -> (usize, String) {
        parse(text).unwrap_err()
    }

    #[test]
    fn parses_by_hand_files() {
        let p = parse(
            "\u{feff}Time, X, Y, Z, Yaw, Pitch\r\n0, 1, 2, 3, 0.5, -0.1\r\n\r\n1e-1,1,2,4,0.5,0\n",
        )
        .unwrap();
        assert_eq!(p.len(), 2);
        assert_eq!(p.poses[1].time, 0.1);
        assert_eq!(p.poses[0].pitch, -0.1);
    }

    #[test]
    fn bad_lines_name_their_number() {
        assert_eq!(err("").0, 1);
        assert_eq!(err("x,y,z\n0,0,0,0,0,0\n").0, 1);
        assert_eq!(err(HEADER).0, 1);
        assert_eq!(err("time,x,y,z,yaw,pitch\n\n").0, 1);
        let h = |body: &str| format!("{HEADER}\n0,0,0,0,0,0\n{body}\n");
        assert_eq!(err(&h("1,0,0,0,0")).0, 3);
        assert_eq!(err(&h("1,0,0,0,0,0,0")).0, 3);
        assert_eq!(
            err(&h("1,0,zero,0,0,0")),
            (3, "y 'zero' is not a number".into())
        );
        assert_eq!(err(&h("1,0,NaN,0,0,0")).0, 3);
        assert_eq!(err(&h("1,0,0,inf,0,0")).0, 3);
        assert_eq!(err(&h("0,0,0,0,0,0")).0, 3);
        assert_eq!(err(&h("-1,0,0,0,0,0")).0, 3);
        assert_eq!(err(&h("1,0,0,0,0,2")).0, 3);
        assert_eq!(err(&h("\n\n1,0,0,0,0,")).0, 5);
    }
}
