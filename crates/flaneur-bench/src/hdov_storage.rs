//! The `hdov-storage` experiment (Shou 2002 §5.4, §5.8.2, Table 5.2): what each storage
//! scheme of a database's HDoV-tree takes on disk, against the estimates of eqs.
//! 5.7–5.9 and the thesis's 4 GB / 267 MB / 152.8 MB, with the tree's own pages and
//! internal LODs beside them. It reads the tree's head only.
//!
//! The schemes' sizes follow from the share of the tree a cell sees: horizontal stores
//! a V-page per node and cell, the vertical schemes one per *visible* node and cell,
//! so the report gives N_vnode / N_node, the quantity the savings are made of.
//!
//! With fan-outs asked for, it also sizes the schemes of trees over the same objects and
//! viewcells at each of them, without building them ([`Database::hdov_sizes_at`]): a
//! smaller fan-out makes more, smaller nodes, of which a cell sees a smaller share.

use std::path::Path;

use crate::report::Report;
use flaneur::database::Database;
use flaneur::error::Result;
use flaneur::hdov::{FanoutSizes, Scheme};

/// Table 5.2 of the thesis, bytes.
pub const THESIS_TABLE_5_2: [(Scheme, f64); 3] = [
    (Scheme::Horizontal, 4.0 * 1024.0 * 1024.0 * 1024.0),
    (Scheme::Vertical, 267.0 * 1024.0 * 1024.0),
    (Scheme::Indexed, 152.8 * 1024.0 * 1024.0),
];

/// One scheme as stored.
#[derive(Clone, Debug, serde::Serialize)]
pub struct HdovStorageRow {
    pub scheme: Scheme,
    pub bytes: u64,
    pub pages: u32,
    /// Eqs. 5.7–5.9 for this tree (heads and directories aside).
    pub estimate_bytes: u64,
    /// Its bytes over the horizontal scheme's (that eq. 5.7 estimates when the database
    /// does not hold it).
    pub share_of_horizontal: f64,
}

/// What the experiment measured.
#[derive(Clone, Debug, serde::Serialize)]
pub struct HdovStorageReport {
    pub objects: u64,
    pub nodes: u32,
    pub cells: usize,
    pub vpage_len: u32,
    /// N_vnode summed over the cells, and over N_node · C.
    pub visible_nodes: u64,
    pub visible_share: f64,
    /// The tree's build time, its internal LODs' pages, and the database's pages.
    pub build_seconds: f64,
    pub lod_pages: u64,
    pub database_pages: u64,
    pub page_size: usize,
    pub rows: Vec<HdovStorageRow>,
    /// The schemes of trees over the same objects and cells at other fan-outs.
    pub fanouts: Vec<FanoutSizes>,
}

/// Reads what `db`'s HDoV-tree takes, and sizes the schemes at each of `fanouts`.
pub fn run(db: &Database, fanouts: &[u32]) -> Result<HdovStorageReport> {
    let head = db.hdov_head()?;
    let (c, n, nv) = (
        head.cells.len() as u64,
        head.nodes as u64,
        head.visible_nodes,
    );
    let estimate = |s: Scheme| head.estimate(s);
    let horizontal = head
        .schemes
        .iter()
        .find(|s| s.0 == Scheme::Horizontal)
        .map_or(estimate(Scheme::Horizontal), |s| s.1.byte_len as u64);
    let rows = head
        .schemes
        .iter()
        .map(|&(scheme, e)| HdovStorageRow {
            scheme,
            bytes: e.byte_len as u64,
            pages: e.page_count,
            estimate_bytes: estimate(scheme),
            share_of_horizontal: e.byte_len as f64 / horizontal.max(1) as f64,
        })
        .collect();
    Ok(HdovStorageReport {
        objects: db.objects(),
        nodes: head.nodes,
        cells: head.cells.len(),
        vpage_len: head.vpage_len,
        visible_nodes: nv,
        visible_share: nv as f64 / (n * c).max(1) as f64,
        build_seconds: head.seconds,
        lod_pages: head.lod_pages,
        database_pages: db.store().page_count(),
        page_size: db.store().page_size(),
        rows,
        fanouts: fanouts
            .iter()
            .map(|&m| db.hdov_sizes_at(m))
            .collect::<Result<_>>()?,
    })
}

impl Report for HdovStorageReport {
    fn name(&self) -> &'static str {
        "hdov-storage"
    }

    /// One line per scheme stored.
    fn to_csv(&self) -> String {
        let mut s = String::from("scheme,bytes,pages,estimate_bytes,share_of_horizontal\n");
        for r in &self.rows {
            s.push_str(&format!(
                "{},{},{},{},{:.5}\n",
                r.scheme.name(),
                r.bytes,
                r.pages,
                r.estimate_bytes,
                r.share_of_horizontal
            ));
        }
        s
    }

    /// One line per fan-out sized.
    fn extra_csvs(&self) -> Vec<(&'static str, String)> {
        if self.fanouts.is_empty() {
            return Vec::new();
        }
        let mut s = String::from(
            "fanout,nodes,height,cells,visible_nodes,visible_share,horizontal_bytes,\
             vertical_bytes,indexed_bytes,indexed_of_horizontal\n",
        );
        for f in &self.fanouts {
            s.push_str(&format!(
                "{},{},{},{},{},{:.5},{},{},{},{:.5}\n",
                f.fanout,
                f.nodes,
                f.height,
                f.cells,
                f.visible_nodes,
                f.visible_share(),
                f.bytes(Scheme::Horizontal),
                f.bytes(Scheme::Vertical),
                f.bytes(Scheme::Indexed),
                f.share_of_horizontal(Scheme::Indexed)
            ));
        }
        vec![("hdov-storage-fanouts.csv", s)]
    }

    fn markdown(&self) -> String {
        let mib = |b: f64| b / 1048576.0;
        let mut s = format!(
            "# HDoV-tree storage (Shou 2002 §5.4, Table 5.2)\n\n\
             {} objects, an HDoV-tree of {} nodes, {} viewcells, {}-byte V-pages; a cell sees \
             {:.1} % of the tree's nodes (N_vnode / N_node). The tree took {:.1} s to build, its \
             internal LODs {} pages of the database's {} ({} bytes each).\n\n\
             | scheme | bytes | MiB | eqs. 5.7–5.9 | of horizontal | thesis (Table 5.2) |\n|---|---|---|---|---|---|\n",
            self.objects,
            self.nodes,
            self.cells,
            self.vpage_len,
            100.0 * self.visible_share,
            self.build_seconds,
            self.lod_pages,
            self.database_pages,
            self.page_size
        );
        for r in &self.rows {
            let thesis = THESIS_TABLE_5_2
                .iter()
                .find(|t| t.0 == r.scheme)
                .map_or(0.0, |t| t.1);
            s.push_str(&format!(
                "| {} | {} | {:.2} | {} | {:.3} | {:.1} MiB |\n",
                r.scheme.name(),
                r.bytes,
                mib(r.bytes as f64),
                r.estimate_bytes,
                r.share_of_horizontal,
                mib(thesis)
            ));
        }
        s.push_str(
            "\nThe thesis's vertical scheme is 1/15 and its indexed-vertical 1/27 of the \
             horizontal one; here the ratio follows the share of the tree a cell sees.\n",
        );
        if !self.fanouts.is_empty() {
            s.push_str(
                "\n## At other fan-outs\n\nThe same objects and viewcells packed into trees \
                 of other fan-outs (M entries a node, V-pages of 8·M bytes), sized by eqs. \
                 5.7–5.9 without building them (heads and directories aside).\n\n\
                 | fan-out | nodes | height | visible nodes a cell | of the nodes | horizontal MiB \
                 | vertical MiB | indexed MiB | indexed of horizontal |\n\
                 |---|---|---|---|---|---|---|---|---|\n",
            );
            for f in &self.fanouts {
                s.push_str(&format!(
                    "| {} | {} | {} | {:.1} | {:.1} % | {:.2} | {:.2} | {:.2} | 1/{:.1} |\n",
                    f.fanout,
                    f.nodes,
                    f.height,
                    f.visible_nodes as f64 / f.cells.max(1) as f64,
                    100.0 * f.visible_share(),
                    mib(f.bytes(Scheme::Horizontal) as f64),
                    mib(f.bytes(Scheme::Vertical) as f64),
                    mib(f.bytes(Scheme::Indexed) as f64),
                    1.0 / f.share_of_horizontal(Scheme::Indexed).max(f64::MIN_POSITIVE)
                ));
            }
        }
        s
    }

    /// Nothing to plot: the table is the figure.
    fn plot(&self, _dir: &Path) -> Result<()> {
        Ok(())
    }
}
