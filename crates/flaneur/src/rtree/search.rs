//! The one traversal every query kind shares. A query is a `Selection`: which
//! subtrees to enter and which leaf entries to return. Nodes are read straight from
//! their pages through `NodeView`, without decoding them whole.

use super::node::{NodeView, ObjectEntry};
use super::{corrupt, RTree};
use crate::error::Result;
use crate::geom::Aabb;
use crate::store::{NodeHint, PageSource};

/// What a query selects. `descend` is asked of internal entries (subtree MBRs),
/// `select` of leaf entries (object boxes).
pub trait Selection {
    fn descend(&self, mbr: &Aabb) -> bool;
    fn select(&self, bounds: &Aabb) -> bool;
}

/// The objects a query returned and the pages it read, in the order it read them.
///
/// ```
/// # fn main() -> flaneur::Result<()> {
/// # let dir = tempfile::tempdir().unwrap();
/// # let (scene, path) = (dir.path().join("c.scene"), dir.path().join("c.flaneur"));
/// # citygen::write_city(&citygen::CityConfig { objects: 40, landmarks: 0.0, ..Default::default() }, &scene)?;
/// # flaneur::build_from_scene(&scene, &path, &Default::default())?;
/// let db = flaneur::Database::open(&path)?;
/// let all = db.range(&db.bounds())?;
/// assert_eq!(all.ids().len(), 40);
/// assert!(all.pages.contains(&db.tree().root)); // every query starts at the root
/// # Ok(()) }
/// ```
#[derive(Clone, Debug, Default, PartialEq)]
pub struct QueryResult {
    /// The objects found.
    pub objects: Vec<ObjectEntry>,
    /// The node pages the query read, in the order it read them.
    pub pages: Vec<u64>,
}

impl QueryResult {
    /// The ids of the objects, sorted.
    pub fn ids(&self) -> Vec<u64> {
        let mut ids: Vec<u64> = self.objects.iter().map(|o| o.id).collect();
        ids.sort_unstable();
        ids
    }
}

pub(crate) fn search<S: Selection, P: PageSource + ?Sized>(
    tree: &RTree,
    pages: &P,
    sel: &S,
    query: &Aabb,
) -> Result<QueryResult> {
    pages.begin_search(query);
    let result = traverse(tree, pages, sel);
    pages.end_search();
    result
}

/// The most nodes a look-ahead visits: it only plans reads, and must stay cheap.
const LOOK_AHEAD_NODES: usize = 4096;

/// Looks ahead through the nodes held without a round trip (a remote store's cache,
/// which its first round trip filled with the tree's upper levels) and fetches, together,
/// every node the search will reach first that is not held. Over HTTP a first query then
/// waits once for its leaves instead of once per node above them. Reads and counts
/// nothing; a page that fails its checks is left for the traversal to name.
fn fetch_frontier<S: Selection, P: PageSource + ?Sized>(tree: &RTree, pages: &P, sel: &S) {
    let mut buf = Vec::new();
    let mut frontier = Vec::new();
    let mut queue = vec![(tree.root, tree.height.saturating_sub(1) as u16)];
    let mut visited = 0;
    while let Some((page, level)) = queue.pop() {
        visited += 1;
        if visited > LOOK_AHEAD_NODES {
            break;
        }
        if !pages.peek_node(page, &mut buf) {
            frontier.push(page);
            continue;
        }
        let Ok(node) = NodeView::parse(&buf) else {
            continue;
        };
        if node.level != level || node.is_leaf() {
            continue;
        }
        for i in 0..node.len() {
            let child = node.child(i);
            if sel.descend(&child.mbr) {
                queue.push((child.page, level - 1));
            }
        }
    }
    pages.will_read(&frontier);
}

fn traverse<S: Selection, P: PageSource + ?Sized>(
    tree: &RTree,
    pages: &P,
    sel: &S,
) -> Result<QueryResult> {
    fetch_frontier(tree, pages, sel);
    let mut result = QueryResult::default();
    let mut buf = Vec::with_capacity(4096);
    let height = tree.height;
    // Levels must fall by one per step down: a corrupt child pointer cannot loop.
    let mut stack = vec![(
        tree.root,
        NodeHint {
            level: height.saturating_sub(1) as u16,
            height,
            mbr: Aabb::EMPTY,
        },
    )];
    while let Some((page, hint)) = stack.pop() {
        pages.read_node(page, &hint, &mut buf)?;
        result.pages.push(page);
        let level = hint.level;
        let node = NodeView::parse(&buf).map_err(|w| corrupt(pages.path(), page, w))?;
        if node.level != level {
            return Err(corrupt(
                pages.path(),
                page,
                format!(
                    "node at level {} where level {level} was expected",
                    node.level
                ),
            ));
        }
        if node.is_leaf() {
            for i in 0..node.len() {
                if sel.select(&node.mbr(i)) {
                    result.objects.push(node.object(i));
                }
            }
        } else {
            let before = stack.len();
            for i in (0..node.len()).rev() {
                let child = node.child(i);
                if sel.descend(&child.mbr) {
                    stack.push((
                        child.page,
                        NodeHint {
                            level: level - 1,
                            height,
                            mbr: child.mbr,
                        },
                    ));
                }
            }
            // The children this node sends the search to, fetched together.
            let next: Vec<u64> = stack[before..].iter().map(|(p, _)| *p).collect();
            pages.will_read(&next);
        }
    }
    Ok(result)
}
