//! `flaneur insert`: adds the objects of OBJ files to a built database, one crash-atomic
//! insert each.

use std::path::PathBuf;

use anyhow::{Context, Result};

use crate::cli::args::finite_f32;

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
    /// The axis that points up in the OBJ files: `y` (as flaneur), `z` (turned to y up),
    /// or `auto`, y unless their bounds plainly say z (as `build` decides).
    #[arg(long, value_name = "y|z|auto", default_value = "auto")]
    up: flaneur::scene::Up,
    /// Metres per unit of the OBJ files (0.01 for centimetres, 0.3048 for feet).
    #[arg(long, value_name = "METRES", default_value_t = 1.0, value_parser = finite_f32, allow_negative_numbers = true)]
    scale: f32,
}

impl InsertArgs {
    /// Reads every OBJ first (a malformed one inserts nothing), then inserts the objects
    /// one by one, each durable and atomic when the next begins.
    pub fn run(self) -> Result<()> {
        let mut named = Vec::new();
        for path in &self.objs {
            named.extend(flaneur::scene::load_obj(path)?);
        }
        // Placed together, by the bounds of them all, as a build places its OBJ inputs.
        let (names, mut meshes): (Vec<String>, Vec<flaneur::scene::Mesh>) =
            named.into_iter().unzip();
        let axes = flaneur::scene::ObjAxes {
            up: self.up,
            scale: self.scale,
        };
        let placed = flaneur::scene::place(&mut meshes, &axes)?;
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
        for (i, (name, mesh)) in names.iter().zip(&meshes).enumerate() {
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
        super::build::print_placed(&placed);
        Ok(())
    }
}
