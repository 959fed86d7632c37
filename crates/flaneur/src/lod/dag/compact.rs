//! The DAG's encoding in format version 2: the same content as version 1 (`codec`),
//! every count and index as a varint of what is small about it, the attributes as byte
//! planes of bfloat16s rounded up (bounds stay bounds, at most 1/128 looser), so that
//! zstd (the layer outside, `lod::stored`) meets like bytes together. A
//! node's parents lie just below it in the topological order, so they are stored as
//! distances down from it.
//!
//! ```text
//! offset  width  field
//! ------  -----  -----------------------------------------------------------------
//!      0      4  magic          b"FDAG"
//!      4      4  version        u32, DAG_VERSION_PACKED
//!      8      4  construction   u32: 0 full-, 1 non-, 2 mini-redundant
//!     12      4  nodes          u32, n
//!     16      4  splits         u32, s
//!     20      4  edges          u32, e
//!     24      …  body           in this order:
//!                  runs         varint × n: each node's splits − 1
//!                  parents      varint × n: how many; then each node's, highest
//!                               first: k − 1 − the highest, then gaps − 1
//!                  radius       u16 × n as two byte planes, low byte first: the
//!                               f32's high half, rounded up (a bfloat16)
//!                  cone_sin     the same
//!                  error        the same
//!      …      4  crc32          of every byte before it
//! ```
//!
//! Reading checks the header, the checksum, that the body is read through exactly and
//! every value fits, then the content as version 1 does (`checked`), naming the
//! first failure as an `Error::Invalid`, never a panic, whatever the bytes.

use super::attrs::NodeAttrs;
use super::build::{Csr, DagConstruction};
use super::checked::{checked, DAG_MAGIC};
use super::graph::Dag;
use crate::error::{Error, Result};
use crate::store::framing::{self as bytes, push_crc, push_varint, u32_at, Cursor};

/// The encoding version of a DAG packed as varints and byte planes (format version 2).
pub(crate) const DAG_VERSION_PACKED: u32 = 2;

const CONSTRUCTION_OFFSET: usize = 8;
const NODES_OFFSET: usize = 12;
const SPLITS_OFFSET: usize = 16;
const EDGES_OFFSET: usize = 20;
const BODY_OFFSET: usize = 24;

fn corrupt(what: String) -> Error {
    Error::Invalid(format!("LOD DAG bytes (packed): {what}"))
}

/// The high half of `v`'s bits (a bfloat16: 8 bits of mantissa), rounded away from zero
/// so that a stored radius, cone or error is never smaller than the exact one, at most
/// 1/128 larger. The attributes' low bits are noise to zstd, and the traversal's tests
/// only need bounds.
fn rounded_up(v: f32) -> u16 {
    let bits = v.to_bits();
    let high = (bits >> 16) as u16;
    let up = if bits & 0xffff != 0 { high + 1 } else { high };
    // Past the largest finite bfloat16 the bound would read back as infinite.
    if up & 0x7f80 == 0x7f80 && high & 0x7f80 != 0x7f80 {
        high
    } else {
        up
    }
}

impl Dag {
    /// The DAG in format version 2's encoding (layout in this module's source), for
    /// [`from_bytes`](Dag::from_bytes): what [`to_bytes`](Dag::to_bytes) holds, packed,
    /// each attribute rounded up to 8 bits of mantissa.
    ///
    /// ```
    /// use flaneur::lod::{Dag, DagConstruction, ProgressiveMesh};
    /// let pm = ProgressiveMesh::build(&flaneur::scene::bunny())?;
    /// let dag = Dag::build(&pm, DagConstruction::MiniRedundant)?;
    /// let packed = dag.to_packed_bytes();
    /// assert!(2 * packed.len() < dag.to_bytes().len());
    /// let back = Dag::from_bytes(&packed)?;
    /// assert_eq!(back.node_count(), dag.node_count());
    /// assert!(back.attrs(0).radius >= dag.attrs(0).radius);
    /// # Ok::<(), flaneur::Error>(())
    /// ```
    pub fn to_packed_bytes(&self) -> Vec<u8> {
        let n = self.node_count();
        let mut b = Vec::with_capacity(BODY_OFFSET + 16 * n);
        b.extend_from_slice(&DAG_MAGIC);
        for field in [
            DAG_VERSION_PACKED,
            self.edges.construction.code(),
            n as u32,
            self.split_count() as u32,
            self.edge_count() as u32,
        ] {
            b.extend_from_slice(&field.to_le_bytes());
        }
        for w in self.edges.run_starts.windows(2) {
            push_varint(&mut b, (w[1] - w[0] - 1) as u64);
        }
        let parents = &self.edges.parents;
        for k in 0..n {
            push_varint(&mut b, parents.row(k).len() as u64);
        }
        for k in 0..n {
            let mut above = k as u32;
            for &p in parents.row(k).iter().rev() {
                push_varint(&mut b, (above - 1 - p) as u64);
                above = p;
            }
        }
        let fields: [fn(&NodeAttrs) -> f32; 3] = [|a| a.radius, |a| a.cone_sin, |a| a.error];
        for field in fields {
            for k in 0..2 {
                b.extend(
                    self.attrs
                        .iter()
                        .map(|a| rounded_up(field(a)).to_le_bytes()[k]),
                );
            }
        }
        push_crc(&mut b);
        b
    }
}

/// Reads the bytes [`Dag::to_packed_bytes`] writes (magic and version already seen by
/// `from_bytes`).
pub(super) fn decode(b: &[u8]) -> Result<Dag> {
    let body = bytes::checked_body(b, BODY_OFFSET).map_err(corrupt)?;
    let code = u32_at(b, CONSTRUCTION_OFFSET);
    let construction = DagConstruction::from_code(code)
        .ok_or_else(|| corrupt(format!("unknown construction {code}")))?;
    let (n, s, e) = (
        u32_at(b, NODES_OFFSET) as usize,
        u32_at(b, SPLITS_OFFSET),
        u32_at(b, EDGES_OFFSET) as usize,
    );
    // A node takes 8 bytes at least, an edge 1: counts that promise more than the
    // body holds are refused before anything is allocated for them.
    bytes::at_least(
        body.len(),
        8 * n as u64 + e as u64,
        "its counts take at least",
    )
    .map_err(corrupt)?;
    let mut c = Cursor::new(body);
    let (run_starts, parents, attrs) = read_body(&mut c, n, e).map_err(corrupt)?;
    if c.left() != 0 {
        return Err(corrupt(format!("{} trailing bytes", c.left())));
    }
    checked(construction, run_starts, parents, attrs, s).map_err(corrupt)
}

fn read_body(
    c: &mut Cursor,
    n: usize,
    e: usize,
) -> std::result::Result<(Vec<u32>, Csr, Vec<NodeAttrs>), String> {
    let mut run_starts = Vec::with_capacity(n + 1);
    run_starts.push(0u32);
    for k in 0..n {
        let end = run_starts[k] as u64 + c.varint(u32::MAX as u64, "runs")? + 1;
        run_starts.push(u32::try_from(end).map_err(|_| format!("node {k}'s run ends at {end}"))?);
    }
    let mut starts = Vec::with_capacity(n + 1);
    starts.push(0u32);
    for k in 0..n {
        let end = starts[k] as u64 + c.varint(u32::MAX as u64, "parent counts")?;
        if end > e as u64 {
            return Err(format!(
                "node {k}'s parent list ends at {end}, past {e} edges"
            ));
        }
        starts.push(end as u32);
    }
    let mut items = vec![0u32; e];
    for k in 0..n {
        let row = &mut items[starts[k] as usize..starts[k + 1] as usize];
        let mut above = k as u64;
        for p in row.iter_mut().rev() {
            let gap = c.varint(u32::MAX as u64, "parents")? + 1;
            above = above
                .checked_sub(gap)
                .ok_or_else(|| format!("node {k}'s parents are not below it"))?;
            *p = above as u32;
        }
    }
    let mut planes = [const { Vec::new() }; 3];
    for plane in &mut planes {
        *plane = c
            .planes::<2>(n, "attributes")?
            .into_iter()
            .map(|h| f32::from_bits((u16::from_le_bytes(h) as u32) << 16))
            .collect::<Vec<f32>>();
    }
    let attrs = (0..n)
        .map(|k| NodeAttrs {
            radius: planes[0][k],
            cone_sin: planes[1][k],
            error: planes[2][k],
        })
        .collect();
    Ok((run_starts, Csr { starts, items }, attrs))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::lod::fixtures::{building, grid};
    use crate::lod::ProgressiveMesh;
    use crate::store::framing::{mangled, refuses_every_damage, reseal};

    fn dag_of(mesh: &crate::scene::Mesh) -> Dag {
        let pm = ProgressiveMesh::build(mesh).unwrap();
        Dag::build(&pm, DagConstruction::MiniRedundant).unwrap()
    }

    #[test]
    fn round_trips_in_fewer_bytes() {
        for mesh in [crate::scene::bunny(), building(), grid(6)] {
            for construction in [
                DagConstruction::FullRedundant,
                DagConstruction::NonRedundant,
                DagConstruction::MiniRedundant,
            ] {
                let pm = ProgressiveMesh::build(&mesh).unwrap();
                let dag = Dag::build(&pm, construction).unwrap();
                let packed = dag.to_packed_bytes();
                let back = Dag::from_bytes(&packed).unwrap();
                assert_eq!((&back.edges, &back.roots), (&dag.edges, &dag.roots));
                for (b, a) in back.attrs.iter().zip(&dag.attrs) {
                    let pairs = [
                        (b.radius, a.radius),
                        (b.cone_sin, a.cone_sin),
                        (b.error, a.error),
                    ];
                    for (b, a) in pairs {
                        assert!(a <= b && b <= a * (1.0 + 1.0 / 128.0), "{a} stored as {b}");
                    }
                }
                assert!(2 * packed.len() < dag.to_bytes().len());
            }
        }
    }

    #[test]
    fn attributes_round_up() {
        let cases = [
            (0.0, 0.0),
            (1.0, 1.0),
            (1.0 + f32::EPSILON, 1.0 + 1.0 / 128.0),
            (0.999, 1.0),
        ];
        for (v, up) in cases {
            assert_eq!(f32::from_bits((rounded_up(v) as u32) << 16), up, "{v}");
        }
        assert!(f32::from_bits((rounded_up(f32::MAX) as u32) << 16).is_finite());
    }

    #[test]
    fn every_truncation_and_every_flipped_byte_is_an_error() {
        refuses_every_damage(&dag_of(&building()).to_packed_bytes(), Dag::from_bytes);
    }

    #[test]
    fn resealed_bad_content_is_named() {
        let dag = dag_of(&building());
        let bad = |edit: &dyn Fn(&mut Dag)| {
            let mut d = dag.clone();
            edit(&mut d);
            Dag::from_bytes(&d.to_packed_bytes())
                .unwrap_err()
                .to_string()
        };
        let err = bad(&|d| d.attrs[2].cone_sin = 1.5);
        assert!(err.contains("out of range"), "{err}");
        let err = bad(&|d| d.attrs[1].error = f32::NAN);
        assert!(err.contains("out of range"), "{err}");
        let mut b = dag.to_packed_bytes();
        b[SPLITS_OFFSET..SPLITS_OFFSET + 4]
            .copy_from_slice(&(dag.split_count() as u32 + 1).to_le_bytes());
        reseal(&mut b);
        let err = Dag::from_bytes(&b).unwrap_err().to_string();
        assert!(err.contains("the runs cover"), "{err}");
        // A parent as far below the node as it can go, and one further.
        let k = (0..dag.node_count())
            .find(|&k| !dag.edges.parents.row(k).is_empty())
            .unwrap();
        let mut b = dag.to_packed_bytes();
        let mut prefix = Vec::new();
        for w in dag.edges.run_starts.windows(2) {
            push_varint(&mut prefix, (w[1] - w[0] - 1) as u64);
        }
        for r in 0..dag.node_count() {
            push_varint(&mut prefix, dag.edges.parents.row(r).len() as u64);
        }
        // Nodes before k have no parents: k's first parent's varint comes next.
        let at = BODY_OFFSET + prefix.len();
        assert!(k < 128 && b[at] < 0x80);
        b[at] = k as u8;
        reseal(&mut b);
        let err = Dag::from_bytes(&b).unwrap_err().to_string();
        assert!(err.contains("not below it"), "{err}");
    }

    #[test]
    fn random_bytes_never_panic() {
        let good = dag_of(&grid(4)).to_packed_bytes();
        let restore = |b: &mut [u8]| {
            b[..4].copy_from_slice(&DAG_MAGIC);
            b[4..8].copy_from_slice(&DAG_VERSION_PACKED.to_le_bytes());
            reseal(b);
        };
        mangled(13, 3000, 300, &good, restore, |b| {
            let _ = Dag::from_bytes(b);
        });
    }
}
