//! `flaneur insert`: adds the objects of OBJ files to a built database, one crash-atomic
//! insert each.

use std::path::PathBuf;

use anyhow::{Context, Result};

use flaneur::{Backend, Database};

/// `flaneur insert`'s arguments.
#[derive(clap::Args)]
pub struct InsertArgs {
    /// The database to add to (a file; it is opened for writing).
    db: PathBuf,
    /// OBJ files: every object or group of each becomes one object.
    #[arg(required = true)]
    objs: Vec<PathBuf>,
    /// The first new object's id; the others follow. Default: one past the largest id
    /// the database holds.
    #[arg(long, value_name = "ID")]
    first_id: Option<u64>,
}

impl InsertArgs {
    /// Reads every OBJ first (a malformed one inserts nothing), then inserts the objects
    /// one by one, each durable and atomic when the next begins.
    pub fn run(self) -> Result<()> {
        let mut meshes = Vec::new();
        for path in &self.objs {
            meshes.extend(flaneur::scene::load_obj(path)?);
        }
        let mut db = Database::open_writable(&self.db, Backend::Mmap)?;
        let first = match self.first_id {
            Some(id) => id,
            None if db.objects() == 0 => 0,
            None => {
                let all = db.range(&db.bounds())?;
                all.ids().into_iter().max().map_or(0, |m| m + 1)
            }
        };
        let pages = db.store().page_count();
        for (i, (name, mesh)) in meshes.iter().enumerate() {
            let id = first + i as u64;
            db.insert(id, mesh)
                .with_context(|| format!("inserting object {name:?} as id {id}"))?;
        }
        println!(
            "inserted {} objects (ids {first}..{}), {} pages appended; the database holds {}",
            meshes.len(),
            first + meshes.len() as u64,
            db.store().page_count() - pages,
            db.objects()
        );
        Ok(())
    }
}
