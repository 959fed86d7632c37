//! What an OpenStreetMap import did with each building it met: imported, repaired on the
//! way in, or skipped, counted by reason for the build's summary.

use std::collections::BTreeMap;

/// Why a building was not imported.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, serde::Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Skip {
    /// A node of its outline is not in the extract (cut off at the extract's edge).
    MissingNodes,
    /// A member way of its multipolygon is not in the extract.
    MissingWays,
    /// Its outline does not close: a way whose ends differ, or member ways that do not
    /// join end to end.
    Unclosed,
    /// A ring with fewer than three distinct corners.
    TooFewCorners,
    /// No outer ring with an area (zero-area ways, a multipolygon without outers).
    NoArea,
    /// Edges of its rings cross.
    SelfIntersecting,
    /// Its base (`min_height`, `building:min_level`) is at or above its top.
    BaseAboveTop,
    /// A corner at a latitude or longitude that is not one.
    BadCoordinates,
    /// The triangulator found no triangles for its roof.
    Untriangulated,
    /// A way tagged as a building that is also an outer ring of a building
    /// multipolygon: the multipolygon draws it.
    DrawnByRelation,
}

impl Skip {
    /// The reason in words, for the build's summary.
    pub fn describe(self) -> &'static str {
        match self {
            Skip::MissingNodes => "nodes missing from the extract",
            Skip::MissingWays => "multipolygon member ways missing from the extract",
            Skip::Unclosed => "outline not closed",
            Skip::TooFewCorners => "ring of fewer than 3 corners",
            Skip::NoArea => "no area",
            Skip::SelfIntersecting => "rings cross themselves or each other",
            Skip::BaseAboveTop => "min_height at or above its height",
            Skip::BadCoordinates => "node coordinates off the globe",
            Skip::Untriangulated => "roof not triangulated",
            Skip::DrawnByRelation => "way also a building multipolygon's outer, drawn by it",
        }
    }
}

/// What was mended on a building that was imported.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, serde::Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Repair {
    /// Repeated nodes (the same node, or the same place, twice in a row) dropped.
    RepeatedNodes,
    /// A ring under half a square metre dropped from a multipolygon.
    TinyRing,
    /// An inner ring inside no outer ring dropped.
    StrayInner,
    /// A `height` (or `min_height`) tag that is not a length: levels or the default taken.
    UnreadableHeight,
    /// A height over the stated maximum: levels or the default taken.
    AbsurdHeight,
    /// A `roof:shape` other than flat, drawn flat.
    RoofDrawnFlat,
}

impl Repair {
    /// The repair in words, for the build's summary.
    pub fn describe(self) -> &'static str {
        match self {
            Repair::RepeatedNodes => "repeated nodes dropped",
            Repair::TinyRing => "ring under 0.5 m² dropped",
            Repair::StrayInner => "inner ring outside every outer dropped",
            Repair::UnreadableHeight => "unreadable height tag, levels or default used",
            Repair::AbsurdHeight => "height over the maximum, levels or default used",
            Repair::RoofDrawnFlat => "roof shape drawn flat",
        }
    }
}

/// What an OpenStreetMap import made of an extract.
///
/// Each skipped building counts once, under the first reason found; a repaired building
/// counts once under each kind of repair made to it.
#[derive(Clone, Debug, Default, PartialEq, serde::Serialize)]
pub struct OsmReport {
    /// Buildings imported from closed ways.
    pub from_ways: u64,
    /// Buildings imported from multipolygon relations.
    pub from_relations: u64,
    /// Buildings skipped, by reason.
    pub skipped: BTreeMap<Skip, u64>,
    /// Buildings imported after a repair, by repair.
    pub repaired: BTreeMap<Repair, u64>,
    /// The latitude and longitude (degrees) the projection is centred on: the middle of
    /// the buildings' nodes' bounds.
    pub centre: [f64; 2],
}

impl OsmReport {
    /// Buildings imported.
    pub fn buildings(&self) -> u64 {
        self.from_ways + self.from_relations
    }

    /// Buildings skipped, all reasons together.
    pub fn skipped_total(&self) -> u64 {
        self.skipped.values().sum()
    }

    pub(super) fn skip(&mut self, why: Skip) {
        *self.skipped.entry(why).or_default() += 1;
    }

    pub(super) fn count_repairs(&mut self, repairs: &mut Vec<Repair>) {
        repairs.sort_unstable();
        repairs.dedup();
        for r in repairs.drain(..) {
            *self.repaired.entry(r).or_default() += 1;
        }
    }
}
