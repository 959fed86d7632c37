//! Truly selective clients against a hostile server: each input is a vsplit batch's
//! bytes; a batch that decodes is handed to a client of a small torus (placed by cut
//! vertices) and to one of a flat-shaded building (placed by its triangles' leaves),
//! each of which then refines for a view, and to the cut-vertex-only clients of both.
//! Any input must end in an error or a mesh, never a panic.

#![no_main]

use std::sync::OnceLock;

use flaneur::lod::{bumpy_torus, Dag, DagConstruction, ProgressiveMesh, View};
use flaneur::lod::{CutVertexClient, SelectiveClient, SelectiveSource};
use flaneur_stream::selective_wire::decode_vsplits;
use libfuzzer_sys::fuzz_target;

/// The torus's source and the building's, with a view of each.
fn sources() -> &'static [(SelectiveSource, View); 2] {
    static SOURCES: OnceLock<[(SelectiveSource, View); 2]> = OnceLock::new();
    SOURCES.get_or_init(|| {
        let source = |mesh: &flaneur::scene::Mesh| {
            let pm = ProgressiveMesh::build(mesh).unwrap();
            let dag = Dag::build(&pm, DagConstruction::MiniRedundant).unwrap();
            SelectiveSource::new(&pm, &dag).unwrap()
        };
        let building = citygen::sample_building(600).unwrap();
        let p = glam::Vec3::from(building.positions[0]);
        let torus_view = View::new(glam::Vec3::new(0.0, 0.0, 2.0), glam::Vec3::NEG_Z, 1.0);
        let building_view = View::new(p + glam::Vec3::new(0.0, 5.0, 40.0), glam::Vec3::NEG_Z, 1.0);
        [
            (source(&bumpy_torus(600)), torus_view.unwrap()),
            (source(&building), building_view.unwrap()),
        ]
    })
}

fuzz_target!(|data: &[u8]| {
    let Ok(packets) = decode_vsplits(data) else {
        return;
    };
    for (source, view) in sources() {
        let mut client = SelectiveClient::new(source.base());
        if client.receive(&packets).is_ok() {
            let _ = client.select(view, 0.001);
        }
        let _ = CutVertexClient::new(source.base()).receive(&packets);
    }
});
