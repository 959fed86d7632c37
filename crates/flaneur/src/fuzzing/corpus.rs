//! Where the fuzz targets' corpora are (`fuzz/corpus/<target>/`), and their inputs, for
//! the tests that replay them on the stable toolchain in every crate.

use std::path::PathBuf;

/// The corpus folder of `target`, in the repository this crate was built from.
pub fn corpus_dir(target: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("../../fuzz/corpus")
        .join(target)
}

/// Every input of `target`'s corpus with its file name, sorted by name; an error names
/// a folder that cannot be read, or one that holds no input.
pub fn corpus_inputs(target: &str) -> Result<Vec<(String, Vec<u8>)>, String> {
    let dir = corpus_dir(target);
    let read = |e: std::io::Error| format!("the {target} corpus at {}: {e}", dir.display());
    let mut found = Vec::new();
    for entry in std::fs::read_dir(&dir).map_err(read)? {
        let path = entry.map_err(read)?.path();
        let name = path.file_name().map(|n| n.to_string_lossy().into_owned());
        found.push((
            name.unwrap_or_default(),
            std::fs::read(&path).map_err(read)?,
        ));
    }
    if found.is_empty() {
        return Err(format!("the {target} corpus at {} is empty", dir.display()));
    }
    found.sort();
    Ok(found)
}
