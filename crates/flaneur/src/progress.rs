//! How long work tells its caller how far it has got. The engine never draws or prints;
//! a build hands its counts to a [`Progress`] the caller passes, so the CLI can draw
//! bars from them and a program embedding the library can log them or ignore them
//! ([`Silent`]).

/// A step of a long job whose progress is reported.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Step {
    /// A build reading its scene once to learn where each object stands, before it
    /// writes them in their order along the curve; counted in objects.
    Ordering,
    /// A build writing objects (their meshes and LODs); counted in objects.
    Objects,
    /// A build precomputing visibility; counted in viewcells.
    Visibility,
    /// A build making the HDoV-tree's internal LODs; counted in nodes.
    HdovLods,
    /// A build making the HDoV-tree's V-pages; counted in viewcells.
    HdovCells,
    /// Loading the memory scene tree's objects; counted in objects.
    SceneObjects,
    /// Making the scene tree's internal LODs; counted in nodes.
    SceneLods,
}

impl Step {
    /// What the step counts, in the plural: "objects", "cells".
    pub fn unit(self) -> &'static str {
        match self {
            Step::Ordering | Step::Objects => "objects",
            Step::Visibility => "cells",
            Step::HdovLods => "nodes",
            Step::HdovCells => "cells",
            Step::SceneObjects => "objects",
            Step::SceneLods => "nodes",
        }
    }

    /// A short name for the step: "building", "visibility".
    pub fn name(self) -> &'static str {
        match self {
            Step::Ordering => "ordering",
            Step::Objects => "building",
            Step::Visibility => "visibility",
            Step::HdovLods => "HDoV LODs",
            Step::HdovCells => "HDoV V-pages",
            Step::SceneObjects => "scene tree objects",
            Step::SceneLods => "scene tree LODs",
        }
    }
}

/// Receives a long job's progress. Called from the job's threads, so it must be `Sync`.
///
/// ```
/// use std::sync::atomic::{AtomicU64, Ordering};
/// use flaneur::progress::{Progress, Step};
///
/// /// Keeps the last count of objects built.
/// struct Last(AtomicU64);
/// impl Progress for Last {
///     fn update(&self, step: Step, done: u64, _total: Option<u64>) {
///         if step == Step::Objects {
///             self.0.store(done, Ordering::Relaxed);
///         }
///     }
/// }
/// let last = Last(AtomicU64::new(0));
/// last.update(Step::Objects, 12, Some(40));
/// assert_eq!(last.0.load(Ordering::Relaxed), 12);
/// ```
pub trait Progress: Sync {
    /// `done` units of `step` are complete, of `total` where it is known. `done` only
    /// grows within a step; `total` may be learnt late (the first calls may lack it).
    fn update(&self, step: Step, done: u64, total: Option<u64>);

    /// `step` is over (its last update has been given).
    fn finish(&self, _step: Step) {}
}

/// A [`Progress`] that ignores everything.
#[derive(Clone, Copy, Debug, Default)]
pub struct Silent;

impl Progress for Silent {
    fn update(&self, _step: Step, _done: u64, _total: Option<u64>) {}
}
