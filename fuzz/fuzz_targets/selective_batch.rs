//! A truly selective client against a hostile server: each input is a vsplit batch's
//! bytes; a batch that decodes is handed to a client of a small torus, which then
//! refines for a view. Any input must end in an error or a mesh, never a panic.

#![no_main]

use std::sync::OnceLock;

use flaneur::lod::{bumpy_torus, Dag, DagConstruction, ProgressiveMesh, View};
use flaneur::lod::{SelectiveClient, SelectiveSource};
use flaneur_stream::selective_wire::decode_vsplits;
use libfuzzer_sys::fuzz_target;

fn source() -> &'static SelectiveSource {
    static SOURCE: OnceLock<SelectiveSource> = OnceLock::new();
    SOURCE.get_or_init(|| {
        let pm = ProgressiveMesh::build(&bumpy_torus(600)).unwrap();
        let dag = Dag::build(&pm, DagConstruction::MiniRedundant).unwrap();
        SelectiveSource::new(&pm, &dag).unwrap()
    })
}

fuzz_target!(|data: &[u8]| {
    let Ok(packets) = decode_vsplits(data) else {
        return;
    };
    let mut client = SelectiveClient::new(source().base());
    if client.receive(&packets).is_ok() {
        let view = View::new(glam::Vec3::new(0.0, 0.0, 2.0), glam::Vec3::NEG_Z, 1.0).unwrap();
        let _ = client.select(&view, 0.001);
    }
});
