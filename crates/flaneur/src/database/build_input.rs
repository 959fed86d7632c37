//! What a file given as a database holds when it is one of a build's inputs instead: a
//! scene file, an OBJ or glTF model, an OpenStreetMap extract. Opening one as a database
//! fails on its first bytes ("bad magic"); the error then says what the file is, so that
//! the way on (building a database from it) is plain.

use std::io::Read;
use std::path::Path;

use crate::build::{model_format, ModelFormat};
use crate::error::Error;
use crate::scene::SceneReader;

/// A build's input, found where a database was expected.
///
/// ```
/// # let dir = tempfile::tempdir().unwrap();
/// let obj = dir.path().join("house.obj");
/// std::fs::write(&obj, "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n").unwrap();
/// let kind = flaneur::database::BuildInput::of(&obj);
/// assert_eq!(kind, Some(flaneur::database::BuildInput::Model(flaneur::build::ModelFormat::Obj)));
/// let err = flaneur::Database::open(&obj).err().unwrap();
/// assert!(err.to_string().contains("an OBJ model"));
/// ```
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum BuildInput {
    /// A scene file, as citygen writes.
    Scene,
    /// A model file: OBJ, glTF or an OpenStreetMap extract.
    Model(ModelFormat),
}

impl BuildInput {
    /// What the file at `location` is, if a build's input: a scene file or a binary glTF
    /// or an OpenStreetMap extract by its first bytes, else a model by its name (a URL by
    /// its name only). `None` for anything else, a database included.
    pub fn of(location: &Path) -> Option<BuildInput> {
        if !crate::store::is_url(&location.to_string_lossy()) {
            if SceneReader::open(location).is_ok() {
                return Some(BuildInput::Scene);
            }
            let mut first = Vec::new();
            let _ = std::fs::File::open(location).and_then(|f| f.take(16).read_to_end(&mut first));
            if first.starts_with(b"glTF") {
                return Some(BuildInput::Model(ModelFormat::Gltf));
            }
            // A PBF's first blob header: its length (4 bytes), then field 1, the type.
            if first.len() >= 15 && first[4] == 0x0a && &first[6..15] == b"OSMHeader" {
                return Some(BuildInput::Model(ModelFormat::Osm));
            }
        }
        model_format(location).map(BuildInput::Model)
    }

    /// The input in words, with its article: "a scene file", "an OBJ model", ….
    pub fn describe(self) -> &'static str {
        match self {
            BuildInput::Scene => "a scene file",
            BuildInput::Model(ModelFormat::Obj) => "an OBJ model",
            BuildInput::Model(ModelFormat::Gltf) => "a glTF model",
            BuildInput::Model(ModelFormat::Osm) => "an OpenStreetMap extract",
        }
    }
}

/// `e`, when it is a file that is not a database but a build's input, saying so.
pub(super) fn explain(e: Error) -> Error {
    match e {
        Error::NotADatabase { path, what } => {
            let what = match BuildInput::of(&path) {
                Some(input) => format!(
                    "{what}: it is {}, an input to a build, not a database built from one",
                    input.describe()
                ),
                None => what,
            };
            Error::NotADatabase { path, what }
        }
        other => other,
    }
}
