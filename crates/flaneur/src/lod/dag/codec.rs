//! The DAG as flat bytes, for an extent of the database. Little-endian, versioned,
//! checksummed; the children and the roots are not stored but rebuilt from the parents
//! on reading (one pass over the edges), which halves the edge bytes.
//!
//! ```text
//! offset           width  field
//! ---------------  -----  ----------------------------------------------------------
//!               0      4  magic          b"FDAG"
//!               4      4  version        u32, VERSION
//!               8      4  construction   u32: 0 full-, 1 non-, 2 mini-redundant
//!              12      4  nodes          u32, n
//!              16      4  splits         u32, s
//!              20      4  edges          u32, e
//!              24     4n  run ends       u32 per node: node k's splits end here (and
//!                                        k + 1's begin); increasing, the last is s
//!         24 + 4n     4n  parent ends    u32 per node: node k's parents end here in
//!                                        the parent list; non-decreasing, the last is e
//!         24 + 8n     4e  parents        u32 each, every node's ascending, each below
//!                                        the node's own number
//!    24 + 8n + 4e    12n  attributes     per node: radius f32, cone_sin f32, error f32
//!   24 + 20n + 4e      4  crc32          of every byte before it
//! ```
//!
//! Reading checks, in order, and names the first failure: length against the fixed
//! header, magic, version, length against the counts, the checksum, then the content
//! (runs, offsets, edges pointing backward, finite attributes in range), so that bytes
//! that pass are a DAG every traversal can walk without an index check failing.

use super::attrs::NodeAttrs;
use super::build::{Csr, DagConstruction};
use super::checked::{checked, DAG_MAGIC};
use super::graph::Dag;
use crate::error::{Error, Result};
use crate::store::framing::{self as bytes, f32_at, push_crc, u32_at, CRC_LEN};

/// The encoding version this build writes and reads.
pub const DAG_VERSION: u32 = 1;

const MAGIC_OFFSET: usize = 0;
const VERSION_OFFSET: usize = MAGIC_OFFSET + DAG_MAGIC.len();
const CONSTRUCTION_OFFSET: usize = VERSION_OFFSET + 4;
const NODES_OFFSET: usize = CONSTRUCTION_OFFSET + 4;
const SPLITS_OFFSET: usize = NODES_OFFSET + 4;
const EDGES_OFFSET: usize = SPLITS_OFFSET + 4;
const HEADER_LEN: usize = EDGES_OFFSET + 4;
const ATTR_LEN: usize = 12;

/// Where the variable sections begin, for `n` nodes and `e` edges (u64: counts read
/// from damaged bytes must not overflow before the length check rejects them).
struct Sections {
    run_ends: u64,
    parent_ends: u64,
    parents: u64,
    attrs: u64,
    crc: u64,
    total: u64,
}

impl Sections {
    fn new(n: u64, e: u64) -> Sections {
        let run_ends = HEADER_LEN as u64;
        let parent_ends = run_ends + 4 * n;
        let parents = parent_ends + 4 * n;
        let attrs = parents + 4 * e;
        let crc = attrs + ATTR_LEN as u64 * n;
        Sections {
            run_ends,
            parent_ends,
            parents,
            attrs,
            crc,
            total: crc + CRC_LEN as u64,
        }
    }
}

fn corrupt(what: String) -> Error {
    Error::Invalid(format!("LOD DAG bytes: {what}"))
}

impl Dag {
    /// The number of bytes [`to_bytes`](Dag::to_bytes) writes.
    pub fn encoded_len(&self) -> usize {
        Sections::new(self.node_count() as u64, self.edge_count() as u64).total as usize
    }

    /// The DAG as little-endian bytes (layout in this module's source), for
    /// [`from_bytes`](Dag::from_bytes).
    pub fn to_bytes(&self) -> Vec<u8> {
        let mut b = Vec::with_capacity(self.encoded_len());
        b.extend_from_slice(&DAG_MAGIC);
        for field in [
            DAG_VERSION,
            self.edges.construction.code(),
            self.node_count() as u32,
            self.split_count() as u32,
            self.edge_count() as u32,
        ] {
            b.extend_from_slice(&field.to_le_bytes());
        }
        for v in self.edges.run_starts[1..]
            .iter()
            .chain(&self.edges.parents.starts[1..])
            .chain(&self.edges.parents.items)
        {
            b.extend_from_slice(&v.to_le_bytes());
        }
        for a in &self.attrs {
            for f in [a.radius, a.cone_sin, a.error] {
                b.extend_from_slice(&f.to_le_bytes());
            }
        }
        push_crc(&mut b);
        b
    }

    /// Reads a DAG written by [`to_bytes`](Dag::to_bytes) or
    /// [`to_packed_bytes`](Dag::to_packed_bytes). An `Error::Invalid` that
    /// says what is wrong — too short, not a DAG, another version, a checksum mismatch,
    /// or content no DAG can have — never a panic, whatever the bytes.
    pub fn from_bytes(b: &[u8]) -> Result<Dag> {
        if b.len() >= 8 && b[..4] == DAG_MAGIC && u32_at(b, 4) == super::DAG_VERSION_PACKED {
            return super::compact::decode(b);
        }
        bytes::header(b, HEADER_LEN, "a DAG", DAG_MAGIC, DAG_VERSION).map_err(corrupt)?;
        let n = u32_at(b, NODES_OFFSET) as usize;
        let s = u32_at(b, SPLITS_OFFSET);
        let e = u32_at(b, EDGES_OFFSET) as usize;
        let sec = Sections::new(n as u64, e as u64);
        bytes::exactly(
            b.len(),
            sec.total,
            format_args!("{n} nodes and {e} edges take"),
        )
        .map_err(corrupt)?;
        bytes::checksum(b, sec.crc as usize).map_err(corrupt)?;
        let code = u32_at(b, CONSTRUCTION_OFFSET);
        let construction = DagConstruction::from_code(code)
            .ok_or_else(|| corrupt(format!("unknown construction {code}")))?;

        let ends = |at: u64| (0..n).map(move |k| u32_at(b, at as usize + 4 * k));
        let mut run_starts = Vec::with_capacity(n + 1);
        run_starts.push(0u32);
        for (k, end) in ends(sec.run_ends).enumerate() {
            if end <= run_starts[k] {
                return Err(corrupt(format!("node {k} holds no splits")));
            }
            run_starts.push(end);
        }
        let mut starts = Vec::with_capacity(n + 1);
        starts.push(0u32);
        for (k, end) in ends(sec.parent_ends).enumerate() {
            if end < starts[k] || end as usize > e {
                return Err(corrupt(format!("node {k}'s parent list ends at {end}")));
            }
            starts.push(end);
        }
        let items: Vec<u32> = (0..e)
            .map(|i| u32_at(b, sec.parents as usize + 4 * i))
            .collect();
        let attrs = (0..n)
            .map(|k| {
                let at = sec.attrs as usize + ATTR_LEN * k;
                NodeAttrs {
                    radius: f32_at(b, at),
                    cone_sin: f32_at(b, at + 4),
                    error: f32_at(b, at + 8),
                }
            })
            .collect();
        let parents = Csr { starts, items };
        checked(construction, run_starts, parents, attrs, s).map_err(corrupt)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::lod::fixtures::building;
    use crate::lod::ProgressiveMesh;
    use crate::store::framing::{mangled, reseal};

    fn building_dag() -> Dag {
        let pm = ProgressiveMesh::build(&building()).unwrap();
        Dag::build(&pm, DagConstruction::MiniRedundant).unwrap()
    }

    #[test]
    fn round_trips() {
        let pm = ProgressiveMesh::build(&crate::scene::bunny()).unwrap();
        for c in DagConstruction::ALL {
            let dag = Dag::build(&pm, c).unwrap();
            let bytes = dag.to_bytes();
            assert_eq!(bytes.len(), dag.encoded_len());
            assert_eq!(&bytes[..4], b"FDAG");
            assert_eq!(Dag::from_bytes(&bytes).unwrap(), dag);
        }
        let dag = building_dag();
        assert_eq!(Dag::from_bytes(&dag.to_bytes()).unwrap(), dag);
    }

    #[test]
    fn every_truncation_and_every_flipped_byte_is_an_error() {
        let bytes = building_dag().to_bytes();
        for len in 0..bytes.len() {
            let e = Dag::from_bytes(&bytes[..len]).unwrap_err().to_string();
            assert!(e.contains("truncated"), "{len}: {e}");
        }
        for at in 0..bytes.len() {
            let mut b = bytes.clone();
            b[at] ^= 0x5a;
            assert!(Dag::from_bytes(&b).is_err(), "byte {at}");
        }
        let mut longer = bytes.clone();
        longer.push(0);
        assert!(Dag::from_bytes(&longer)
            .unwrap_err()
            .to_string()
            .contains("trailing"));
    }

    #[test]
    fn header_faults_are_named() {
        let bytes = building_dag().to_bytes();
        let with = |at: usize, v: u32| {
            let mut b = bytes.clone();
            b[at..at + 4].copy_from_slice(&v.to_le_bytes());
            Dag::from_bytes(&b).unwrap_err().to_string()
        };
        assert!(with(MAGIC_OFFSET, 0).contains("magic"));
        assert!(with(VERSION_OFFSET, 3).contains("version 3"));
        assert!(with(NODES_OFFSET, u32::MAX).contains("truncated"));
        assert!(with(EDGES_OFFSET, u32::MAX).contains("truncated"));
        assert!(with(SPLITS_OFFSET, 7).contains("checksum"));
    }

    #[test]
    fn resealed_bad_content_is_an_error() {
        // Content faults with a valid checksum: what a buggy writer could produce.
        let dag = building_dag();
        let bytes = dag.to_bytes();
        let (n, e) = (dag.node_count(), dag.edge_count());
        let sec = Sections::new(n as u64, e as u64);
        let child = (1..n as u32).find(|&k| dag.in_degree(k) >= 2).unwrap() as usize;
        let first_parent = sec.parents as usize + 4 * dag.edges.parents.starts[child] as usize;
        let cases: Vec<(usize, u32, &str)> = vec![
            (CONSTRUCTION_OFFSET, 9, "construction"),
            (SPLITS_OFFSET, dag.split_count() as u32 + 1, "cover"),
            (sec.run_ends as usize, 0, "no splits"),
            (
                sec.parent_ends as usize + 4 * (n - 1),
                e as u32 - 1,
                "parent",
            ),
            (sec.parent_ends as usize, e as u32 + 1, "ends at"),
            (first_parent, child as u32, "ascending below"),
            (
                first_parent + 4,
                dag.parents(child as u32)[0],
                "ascending below",
            ),
            (sec.attrs as usize, (-1.0f32).to_bits(), "attributes"),
            (sec.attrs as usize + 4, 1.5f32.to_bits(), "attributes"),
            (sec.attrs as usize + 8, f32::NAN.to_bits(), "attributes"),
        ];
        for (at, v, expect) in cases {
            let mut b = bytes.clone();
            b[at..at + 4].copy_from_slice(&v.to_le_bytes());
            reseal(&mut b);
            let err = Dag::from_bytes(&b).unwrap_err().to_string();
            assert!(err.contains(expect), "at {at}: {err}");
        }
    }

    #[test]
    fn random_bytes_never_panic() {
        let good = building_dag().to_bytes();
        let restore = |b: &mut [u8]| {
            b[..4].copy_from_slice(&DAG_MAGIC);
            reseal(b);
        };
        mangled(5, 2000, 200, &good, restore, |b| {
            let _ = Dag::from_bytes(b);
        });
    }
}
