//! Recorded access sequences: what a pool was asked for, in order, with each access's
//! hint, the box of the search it belonged to and that search's number — enough to
//! replay any policy offline (and Belady's optimum, `belady.rs`) on the same sequence,
//! as Shou 2002 §4.4 and §5.8 compare policies on one walk.
//!
//! The CSV file has a header line and one access per line:
//!
//! ```text
//! search,page,level,height,dov,mbr_x0,mbr_y0,mbr_z0,mbr_x1,mbr_y1,mbr_z1,query_x0,query_y0,query_z0,query_x1,query_y1,query_z1
//! ```
//!
//! Floats are written in their shortest exact form (an unknown box is `inf … -inf`),
//! so a trace reads back equal. Search numbers never decrease. The file holds the
//! accesses only: a trace read back has no lookaheads, so the path policy replays it
//! as LRU that keeps the root.

use std::fs::File;
use std::io::{BufWriter, Write};
use std::path::Path;

use super::frames::Frames;
use super::policy::{Hint, Policy};
use super::stats::CacheStats;
use super::Lookahead;
use crate::error::{Error, Result};
use crate::geom::Aabb;

/// The first line of a trace file.
pub const CSV_HEADER: &str =
    "search,page,level,height,dov,mbr_x0,mbr_y0,mbr_z0,mbr_x1,mbr_y1,mbr_z1,\
query_x0,query_y0,query_z0,query_x1,query_y1,query_z1";
const FIELDS: usize = 17;

/// The most searches one line of a trace file may skip: a replay runs one
/// `end_search` per search.
pub const MAX_SEARCH_GAP: u64 = 1 << 20;

/// One access of a pool.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Access {
    /// The page asked for.
    pub page: u64,
    /// What the requester said of the page.
    pub hint: Hint,
    /// The box of the search in progress (`Aabb::EMPTY` outside one).
    pub query: Aabb,
    /// Searches the pool had ended before this access.
    pub search: u64,
}

/// A walk's prediction of its next searches, as the pool was given it.
#[derive(Clone, Debug, PartialEq)]
pub struct TracedLookahead {
    /// Accesses recorded before it came.
    pub at: usize,
    /// Searches the pool had ended before it came.
    pub search: u64,
    /// The prediction.
    pub ahead: Lookahead,
}

/// An access sequence, in order, with the lookaheads given among the accesses.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Trace {
    /// The accesses, in the order they were made.
    pub accesses: Vec<Access>,
    /// The lookaheads, in the order they were given (`at` never decreases).
    pub lookaheads: Vec<TracedLookahead>,
}

impl Trace {
    /// Accesses in the trace.
    pub fn len(&self) -> usize {
        self.accesses.len()
    }

    /// Whether the trace holds no access.
    pub fn is_empty(&self) -> bool {
        self.accesses.is_empty()
    }

    /// Distinct pages accessed.
    pub fn distinct_pages(&self) -> usize {
        self.accesses
            .iter()
            .map(|a| a.page)
            .collect::<std::collections::HashSet<_>>()
            .len()
    }

    /// Runs `policy` over the sequence in a pool of `capacity_pages` pages, with the
    /// pool's own logic: the same hits, misses and evictions a live pool that started
    /// empty had for the same single-threaded sequence. Between accesses of searches
    /// `s` and `t`, `t − s` searches end; each access sees its own query box; each
    /// lookahead is given where it came, after the searches that had ended by then.
    ///
    /// ```
    /// use flaneur::cache::{Access, Hint, Lru, Trace};
    /// use flaneur::geom::Aabb;
    /// let at = |page| Access { page, hint: Hint::UNKNOWN, query: Aabb::EMPTY, search: 0 };
    /// let t = Trace { accesses: [1, 2, 1, 3, 2].map(at).to_vec(), ..Default::default() };
    /// let s = t.replay(Box::new(Lru::default()), 2);
    /// assert_eq!((s.hits, s.misses, s.evictions), (1, 4, 2));
    /// ```
    pub fn replay(&self, policy: Box<dyn Policy>, capacity_pages: usize) -> CacheStats {
        let mut frames: Frames<()> = Frames::new(policy, capacity_pages);
        let first = |a: Option<u64>, l: Option<u64>| a.into_iter().chain(l).min().unwrap_or(0);
        let mut search = first(
            self.accesses.first().map(|a| a.search),
            self.lookaheads.first().map(|l| l.search),
        );
        let end_until = |frames: &mut Frames<()>, search: &mut u64, to: u64| {
            while *search < to {
                frames.end_search();
                *search += 1;
            }
        };
        let mut lookaheads = self.lookaheads.iter().peekable();
        for (i, a) in self.accesses.iter().enumerate() {
            while let Some(l) = lookaheads.next_if(|l| l.at <= i) {
                end_until(&mut frames, &mut search, l.search);
                frames.look_ahead(&l.ahead);
            }
            end_until(&mut frames, &mut search, a.search);
            frames.begin_search(&a.query);
            if frames.peek(a.page).is_some() {
                frames.hit(a.page, &a.hint);
            } else {
                frames.install(a.page, &a.hint, |_| ());
            }
        }
        frames.stats()
    }

    /// Writes the trace as CSV (see the module comment).
    pub fn write_csv(&self, path: &Path) -> Result<()> {
        let io = |e| Error::io(path, e);
        let mut w = BufWriter::new(File::create(path).map_err(io)?);
        writeln!(w, "{CSV_HEADER}").map_err(io)?;
        for a in &self.accesses {
            let (h, m, q) = (&a.hint, &a.hint.mbr, &a.query);
            writeln!(
                w,
                "{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{}",
                a.search,
                a.page,
                h.level,
                h.height,
                h.dov,
                m.min.x,
                m.min.y,
                m.min.z,
                m.max.x,
                m.max.y,
                m.max.z,
                q.min.x,
                q.min.y,
                q.min.z,
                q.max.x,
                q.max.y,
                q.max.z,
            )
            .map_err(io)?;
        }
        w.into_inner()
            .map_err(|e| io(e.into_error()))?
            .sync_all()
            .map_err(io)
    }

    /// Reads a trace written by [`Trace::write_csv`]. A malformed line is an error
    /// naming the file and the line.
    pub fn read_csv(path: &Path) -> Result<Trace> {
        let text = std::fs::read_to_string(path).map_err(|e| Error::io(path, e))?;
        let bad = |line: usize, what: String| Error::BadInput {
            path: path.to_path_buf(),
            what: format!("line {line}: {what}"),
        };
        let mut lines = text
            .lines()
            .enumerate()
            .map(|(i, l)| (i + 1, l.trim_end_matches('\r')));
        match lines.next() {
            Some((_, h)) if h == CSV_HEADER => {}
            _ => return Err(bad(1, format!("expected the trace header {CSV_HEADER:?}"))),
        }
        let mut accesses = Vec::new();
        let mut last: Option<u64> = None;
        for (n, line) in lines {
            if line.is_empty() {
                continue;
            }
            let a = parse_line(line).map_err(|w| bad(n, w))?;
            if let Some(prev) = last {
                if a.search < prev {
                    return Err(bad(
                        n,
                        format!("search {} comes after search {prev}", a.search),
                    ));
                }
                if a.search - prev > MAX_SEARCH_GAP {
                    return Err(bad(
                        n,
                        format!(
                            "search {} skips more than {MAX_SEARCH_GAP} searches after {prev}",
                            a.search
                        ),
                    ));
                }
            }
            last = Some(a.search);
            accesses.push(a);
        }
        Ok(Trace {
            accesses,
            lookaheads: Vec::new(),
        })
    }
}

fn parse_line(line: &str) -> std::result::Result<Access, String> {
    let f: Vec<&str> = line.split(',').collect();
    if f.len() != FIELDS {
        return Err(format!("{} fields where {FIELDS} were expected", f.len()));
    }
    let names: Vec<&str> = CSV_HEADER.split(',').collect();
    fn num<T: std::str::FromStr>(s: &str, name: &str) -> std::result::Result<T, String> {
        s.trim()
            .parse()
            .map_err(|_| format!("{name} {s:?} is not a valid number"))
    }
    let float = |i: usize| -> std::result::Result<f32, String> {
        let v: f32 = num(f[i], names[i])?;
        if v.is_nan() {
            return Err(format!("{} is not a number", names[i]));
        }
        Ok(v)
    };
    let boxed = |i: usize| -> std::result::Result<Aabb, String> {
        let mut v = [0f32; 6];
        for (k, x) in v.iter_mut().enumerate() {
            *x = float(i + k)?;
        }
        Ok(Aabb {
            min: glam::Vec3::new(v[0], v[1], v[2]),
            max: glam::Vec3::new(v[3], v[4], v[5]),
        })
    };
    Ok(Access {
        search: num(f[0], names[0])?,
        page: num(f[1], names[1])?,
        hint: Hint {
            level: num(f[2], names[2])?,
            height: num(f[3], names[3])?,
            dov: float(4)?,
            mbr: boxed(5)?,
        },
        query: boxed(11)?,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn sample() -> Trace {
        let b = Aabb::new([0.5, -1.0, 1e-7], [3.25, 2.0, 1e9]).unwrap();
        Trace {
            accesses: vec![
                Access {
                    page: 7,
                    hint: Hint {
                        level: 2,
                        height: 3,
                        mbr: Aabb::EMPTY,
                        dov: 0.0,
                    },
                    query: b,
                    search: 4,
                },
                Access {
                    page: 9,
                    hint: Hint {
                        level: 0,
                        height: 3,
                        mbr: b,
                        dov: 0.125,
                    },
                    query: b,
                    search: 4,
                },
                Access {
                    page: 7,
                    hint: Hint::UNKNOWN,
                    query: Aabb::EMPTY,
                    search: 6,
                },
            ],
            lookaheads: Vec::new(),
        }
    }

    #[test]
    fn csv_round_trip() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("t.csv");
        sample().write_csv(&path).unwrap();
        assert_eq!(Trace::read_csv(&path).unwrap(), sample());
        Trace::default().write_csv(&path).unwrap();
        assert!(Trace::read_csv(&path).unwrap().is_empty());
    }

    #[test]
    fn malformed_lines_name_the_file_and_line() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("bad.csv");
        sample().write_csv(&path).unwrap();
        let good = std::fs::read_to_string(&path).unwrap();
        let lines: Vec<&str> = good.lines().collect();
        let cases = [
            (format!("{}\n{}\n1,2,3\n", lines[0], lines[1]), "line 3"),
            (
                format!(
                    "{}\n{}\n{}\n",
                    lines[0],
                    lines[1],
                    lines[2].replacen("9", "x", 1)
                ),
                "line 3",
            ),
            (
                format!("{}\n{}\n{}\n", lines[0], lines[3], lines[1]),
                "line 3",
            ), // search goes back
            (
                format!("{}\n{}\n", lines[0], lines[2].replace("0.125", "NaN")),
                "line 2",
            ),
            (
                format!(
                    "{}\n{}\n",
                    lines[0],
                    lines[2].replacen("9,0,3", "9,70000,3", 1)
                ),
                "line 2",
            ), // level > u16
            ("page,search\n".to_string(), "line 1"),
            (String::new(), "line 1"),
        ];
        for (text, want) in cases {
            std::fs::write(&path, &text).unwrap();
            let e = Trace::read_csv(&path).unwrap_err().to_string();
            assert!(e.contains(want) && e.contains("bad.csv"), "{text:?}: {e}");
        }
        let e = Trace::read_csv(&dir.path().join("missing.csv"))
            .unwrap_err()
            .to_string();
        assert!(e.contains("missing.csv"), "{e}");
    }

    #[test]
    fn replay_ends_searches_between_accesses() {
        use crate::cache::DpLru;
        // QN only (γ = 1): page 1 is used in search 0, page 2 in search 1, page 3 in
        // search 2; at capacity 2 the miss on 3 evicts page 1 (QN 2 against 1).
        let leaf = Hint {
            level: 0,
            height: 2,
            ..Hint::UNKNOWN
        };
        let at = |page, search| Access {
            page,
            hint: leaf,
            query: Aabb::EMPTY,
            search,
        };
        let t = Trace {
            accesses: vec![at(1, 10), at(2, 11), at(3, 12), at(2, 12), at(1, 12)],
            ..Default::default()
        };
        let s = t.replay(Box::new(DpLru::new(0.0, 0.0, 1.0).unwrap()), 2);
        assert_eq!((s.hits, s.misses, s.evictions), (1, 4, 2));
    }
}
