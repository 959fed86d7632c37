//! The scene-tree mode (Shou 2002 ch. 6): the retrieval of a VSC, PB or CONV walk, one
//! frame at a time for the walk session. Each frame the eye's viewcell is found, the
//! tree's VDs brought to it on a change, the tree traversed, and the object buffer
//! brought to what the traversal chose: a representation already held at that level
//! stays, another replaces it (the meshes are the tree's, shared, so nothing is read).
//! The settings and figures are `walk::scene`'s.

use std::collections::HashSet;
use std::sync::Arc;
use std::time::Instant;

use crate::database::Database;
use crate::error::{Error, Result};
use crate::geom::Camera;
use crate::hdov::Selection;
use crate::rtree::ObjectEntry;
use crate::walk::buffer::{mesh_bytes, Loaded, ObjectBuffer};
use crate::walk::cells::viewcell_holding;
use crate::walk::scene::{traverse_screened, SceneErrors, SceneTree, ScreenView, Traversal};
use crate::walk::scene::{SceneConfig, SceneFrame};
use crate::walk::session::{self, Culled, Drawable, FrameAt, Mode};
use crate::walk::sink::{FrameFigures, Viewer};
use crate::walk::walk_lods::WalkLods;

/// A walk over `tree` under `cfg` with the poses coming from `viewer`: the walk session
/// with the scene-tree mode. Each frame's figures go to `each` as the frame ends.
pub(crate) fn walk_live<'db>(
    db: &'db Database,
    tree: &mut SceneTree,
    cfg: &SceneConfig,
    lods: &mut WalkLods<'db>,
    viewer: &mut dyn Viewer,
    mut each: impl FnMut(SceneFrame) -> Result<()>,
) -> Result<()> {
    // The screen rule's errors, read once a walk (its leaves' LOD directories).
    let errors = match cfg.selection {
        Selection::Screen => Some(SceneErrors::load(db, tree)?),
        Selection::Thesis => None,
    };
    let mut mode = Scene {
        db,
        tree,
        cfg,
        errors: errors.as_ref(),
        drawable: Vec::new(),
        pending: None,
    };
    let mut walked = 0;
    session::run_each(&mut mode, viewer, lods, |f| {
        walked += 1;
        each(f)
    })?;
    if walked == 0 {
        return Err(Error::Invalid("the walk had no poses".into()));
    }
    Ok(())
}

struct Scene<'a> {
    db: &'a Database,
    tree: &'a mut SceneTree,
    cfg: &'a SceneConfig,
    /// The representations' errors, under the screen rule.
    errors: Option<&'a SceneErrors>,
    /// What the traversal chose, as keys into the buffer.
    drawable: Vec<u64>,
    pending: Option<(SceneFrame, Instant, u64)>,
}

impl Mode for Scene<'_> {
    type Frame = SceneFrame;

    /// The tree holds the city; the buffer only what a frame draws.
    fn memory_budget(&self) -> usize {
        usize::MAX
    }

    fn retrieve(&mut self, at: FrameAt<'_>, buffer: &mut ObjectBuffer) -> Result<Option<Camera>> {
        let pose = at.pose;
        let camera = at.camera(Some(self.cfg.far))?;
        let pages = self.db.io().page_reads;
        let start = Instant::now();
        let mut frame = SceneFrame {
            frame: at.index,
            time: pose.time,
            ..Default::default()
        };
        frame.cell = viewcell_holding(self.db, pose.position)?;
        if let Some(c) = frame.cell {
            let t = Instant::now();
            self.tree.enter(self.db, c)?;
            frame.update_ms = t.elapsed().as_secs_f64() * 1e3;
        }
        let how = match self.tree.cell() {
            Some(_) => self.cfg.traversal,
            None => {
                frame.conv = true;
                Traversal::Conv
            }
        };
        let t = Instant::now();
        let screen = self.errors.map(|errors| ScreenView {
            eye: camera.position,
            fov_y: camera.fov_y,
            tau: self.cfg.tau,
            errors,
        });
        let chosen = traverse_screened(self.tree, how, &camera.frustum(), screen.as_ref())?;
        frame.traverse_ms = t.elapsed().as_secs_f64() * 1e3;
        frame.visited = chosen.visited;
        frame.drawn = chosen.active.len();
        frame.triangles = chosen.triangles;
        frame.dropped = chosen.dropped;
        frame.ended = chosen.ended;
        frame.too_big = chosen.too_big;
        self.drawable.clear();
        for a in &chosen.active {
            let key = self.tree.key(a.node);
            let node = &self.tree.nodes[a.node as usize];
            if node.object.is_none() {
                frame.internal += 1;
            }
            self.drawable.push(key);
            if buffer.get(key).is_some_and(|o| o.level == a.level) {
                continue;
            }
            let mesh = Arc::clone(&node.levels[a.level]);
            let entry = match node.object {
                Some(id) => self.tree.entries[&id],
                None => ObjectEntry {
                    id: key,
                    bounds: node.bounds,
                    mesh: Default::default(),
                    triangles: a.triangles,
                    kind: 0,
                },
            };
            buffer.replace(Loaded {
                entry,
                bytes: mesh_bytes(&mesh),
                mesh,
                level: a.level,
                finest: a.level,
                finer_of: false,
                dov: None,
                tau_scale: 1.0,
            });
        }
        let keep: HashSet<u64> = self.drawable.iter().copied().collect();
        let gone: Vec<u64> = buffer
            .iter()
            .map(|o| o.entry.id)
            .filter(|id| !keep.contains(id))
            .collect();
        for id in gone {
            buffer.remove(id);
        }
        self.pending = Some((frame, start, pages));
        Ok(Some(camera))
    }

    fn drawable(&self) -> Drawable<'_> {
        Drawable::Only(&self.drawable)
    }

    fn finish(&mut self, _: &Culled<'_>, _: &ObjectBuffer) -> Result<SceneFrame> {
        let (mut frame, start, pages) = self
            .pending
            .take()
            .ok_or_else(|| Error::Invalid("a frame finished before it was retrieved".into()))?;
        frame.frame_ms = start.elapsed().as_secs_f64() * 1e3;
        frame.pages = self.db.io().page_reads - pages;
        Ok(frame)
    }

    fn figures(&mut self, f: &SceneFrame, buffer: &ObjectBuffer) -> FrameFigures {
        FrameFigures {
            pages: f.pages,
            objects_buffered: buffer.len(),
            objects_drawn: f.drawn,
            triangles: f.triangles,
            cell: match f.cell {
                Some(c) => format!(
                    "viewcell {c}, {}: {} nodes drawn ({} internal)",
                    self.cfg.traversal.label(),
                    f.drawn,
                    f.internal
                ),
                None => format!(
                    "outside every viewcell, {}",
                    if f.conv {
                        "CONV".to_string()
                    } else {
                        "the last cell's VDs".to_string()
                    }
                ),
            },
            walk_ms: f.frame_ms,
            ..Default::default()
        }
    }
}
