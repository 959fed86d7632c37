//! The Hierarchical Degree-of-Visibility tree (Shou 2002 ch. 5): one disk-resident tree
//! that answers "what is visible from this viewcell, and at what detail" in a few page
//! reads, joining the spatial hierarchy, the internal LODs of its nodes and each
//! viewcell's degrees of visibility.
//!
//! - The **view-invariant** part (§5.2.2, §5.6): nodes packed over the objects' boxes
//!   (`node` is the page layout), each parent entry carrying its child's h and s
//!   (eqs. 5.3–5.4) and internal LODs made from the children's simplified geometry
//!   by aggregate simplification, each with its error in metres (`lods`).
//! - The **view-variant** part (§5.2.2, §5.5.3): per viewcell, each entry's VD = (DoV,
//!   NVO) summed bottom-up from the visibility table (`vd`), in V-pages stored under
//!   the horizontal, vertical or indexed-vertical scheme (§5.4, [`Scheme`]).
//! - The **search** (§5.3, Fig. 5.4): `search` under a DoV threshold η, reached through [`Database::hdov_search`](crate::Database::hdov_search).
//! - The **memory scene tree** of ch. 6 lives with its walk ([`crate::walk::scene`]): the
//!   city in memory as a k-D tree with this module's internal LODs and VDs, traversed by
//!   VSC(η), PB(n) or CONV.
//!
//! `flaneur build --visibility --hdov …` writes it ([`HdovOptions`]); an open database
//! searches it with [`Database::hdov_search`](crate::Database::hdov_search).
//!
//! The choices the thesis leaves open are named where they are made: the tree has its
//! own pages, packed like the R-tree (`build`); up to three internal LODs per node,
//! their shares and how their errors are measured (`lods`); pointers of 4 bytes
//! (`scheme`); the details of eqs. 5.5–5.6 read as triangle counts
//! ([`level_for_detail`]).

mod build;
mod load;
mod lods;
pub(crate) mod node;
mod scheme;
mod search;
mod sizing;
mod tree;
pub(crate) mod vd;

pub(crate) use build::build_hdov;
pub use build::{HdovOptions, HdovReport, SchemeReport};
pub use load::Representation;
pub(crate) use load::{load, Loader};
pub(crate) use lods::{aggregate, error_above, internal_levels, Reference};
pub use lods::{DIRECT_TRIANGLES, ERROR_SAMPLES, LEVEL_SHARES, MIN_TRIANGLES};
pub(crate) use node::HNodeKind;
pub use scheme::{Scheme, POINTER_LEN};
pub(crate) use search::search;
pub use search::{
    box_distance, level_for_detail, stops, Found, NodeErrors, ScreenRule, ScreenTest, SearchResult,
    Selection, MAXDOV,
};
pub(crate) use sizing::sizes_at;
pub use sizing::FanoutSizes;
pub(crate) use tree::HdovTree;
pub use tree::{ProxyErrors, TreeHead, HDOV_SEGMENT};
pub use vd::Vd;

#[cfg(test)]
mod tests;
