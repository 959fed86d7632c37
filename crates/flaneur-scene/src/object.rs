// What the generator emits: an object id, what kind of thing it is, and its mesh. The
// kind travels in the scene file as one byte, so its numbering is part of the format.

use crate::mesh::Mesh;

/// What an object is. The discriminants are the scene file's kind byte: never renumber.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum ObjectKind {
    /// A detached house with a pitched roof.
    House,
    /// A row of terraced units under one roof.
    Terrace,
    /// A tower in setback tiers.
    Tower,
    /// A procedural sculpture landmark (50,000–200,000 triangles).
    Sculpture,
    /// The Stanford bunny as a landmark (subdivided to ~59,000 triangles).
    Bunny,
}

impl ObjectKind {
    /// Every kind, in discriminant order.
    pub const ALL: [ObjectKind; 5] = [
        ObjectKind::House,
        ObjectKind::Terrace,
        ObjectKind::Tower,
        ObjectKind::Sculpture,
        ObjectKind::Bunny,
    ];

    /// The kind's byte in the scene file.
    pub fn as_u8(self) -> u8 {
        match self {
            ObjectKind::House => 0,
            ObjectKind::Terrace => 1,
            ObjectKind::Tower => 2,
            ObjectKind::Sculpture => 3,
            ObjectKind::Bunny => 4,
        }
    }

    /// The kind for a scene-file byte, or `None` for an unknown byte.
    pub fn from_u8(b: u8) -> Option<ObjectKind> {
        ObjectKind::ALL.get(b as usize).copied()
    }

    /// A lower-case name for reports (`"house"`, `"tower"`, …).
    pub fn name(self) -> &'static str {
        match self {
            ObjectKind::House => "house",
            ObjectKind::Terrace => "terrace",
            ObjectKind::Tower => "tower",
            ObjectKind::Sculpture => "sculpture",
            ObjectKind::Bunny => "bunny",
        }
    }

    /// Whether this kind is a high-detail landmark rather than a building.
    pub fn is_landmark(self) -> bool {
        matches!(self, ObjectKind::Sculpture | ObjectKind::Bunny)
    }
}

/// One object of a city: its id (its position in the scene), its kind and its mesh in
/// world coordinates.
#[derive(Clone, Debug, PartialEq)]
pub struct SceneObject {
    /// The object id, `0..objects` in a generated city.
    pub id: u64,
    /// What it is.
    pub kind: ObjectKind,
    /// Its geometry, in world coordinates (metres, y up).
    pub mesh: Mesh,
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn kind_bytes_round_trip() {
        for k in ObjectKind::ALL {
            assert_eq!(ObjectKind::from_u8(k.as_u8()), Some(k));
        }
        assert_eq!(ObjectKind::from_u8(5), None);
        assert_eq!(ObjectKind::Tower.name(), "tower");
    }
}
