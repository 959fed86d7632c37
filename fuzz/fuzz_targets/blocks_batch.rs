//! A client of El-Sana's blocks against a hostile server: each input is the bytes a
//! server sends, read frame by frame; each BLOCKS that decodes is handed to a client of
//! blocks of the stream server's torus whose cache holds few blocks, which then refines
//! for a view, dropping blocks. Any input must end in an error or a mesh, never a panic.

#![no_main]

use std::sync::OnceLock;

use flaneur::lod::{bumpy_torus, BlockClient, Dag, DagConstruction, ProgressiveMesh, View};
use flaneur::lod::SelectiveSource;
use flaneur_stream::protocol::{receive, Message, MAX_TO_CLIENT};
use libfuzzer_sys::fuzz_target;

/// The torus the stream server's fuzz target serves, as a selective source, and a view
/// close to it.
fn source() -> &'static (SelectiveSource, View) {
    static SOURCE: OnceLock<(SelectiveSource, View)> = OnceLock::new();
    SOURCE.get_or_init(|| {
        let pm = ProgressiveMesh::build(&bumpy_torus(1_000)).unwrap();
        let dag = Dag::build(&pm, DagConstruction::MiniRedundant).unwrap();
        let view = View::new(glam::Vec3::new(0.0, 0.3, 2.0), glam::Vec3::NEG_Z, 1.0).unwrap();
        (SelectiveSource::new(&pm, &dag).unwrap(), view)
    })
}

fuzz_target!(|data: &[u8]| {
    let (source, view) = source();
    let mut client = BlockClient::new(source.base(), 2).with_capacity(4);
    let mut input = data;
    while let Ok(Some((m, _))) = receive(&mut input, MAX_TO_CLIENT) {
        let Message::Blocks { objects, .. } = m else {
            continue;
        };
        for o in objects.iter().filter(|o| o.index == 0) {
            if client.receive(&o.blocks).is_err() || client.select(view, 0.002).is_err() {
                return;
            }
        }
    }
});
