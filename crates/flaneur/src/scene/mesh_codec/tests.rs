use super::*;

/// The triangles of `m` as corner positions and normals, each triangle's corners rotated
/// so that the smallest comes first, sorted: equal for two meshes that draw the same
/// triangles, shaded the same.
fn triangles(m: &Mesh) -> Vec<[[u32; 6]; 3]> {
    let mut t: Vec<[[u32; 6]; 3]> = m
        .indices
        .chunks(3)
        .map(|c| {
            let mut corners = [0, 1, 2].map(|k| {
                let (p, n) = (m.positions[c[k] as usize], m.normals[c[k] as usize]);
                [p[0], p[1], p[2], n[0], n[1], n[2]].map(f32::to_bits)
            });
            let r = (0..3).min_by_key(|&k| corners[k]).unwrap();
            corners.rotate_left(r);
            corners
        })
        .collect();
    t.sort_unstable();
    t
}

/// `m` with every position and normal as format version 2 reads it back.
fn quantised(m: &Mesh, grid: &Grid) -> Mesh {
    Mesh {
        positions: m
            .positions
            .iter()
            .map(|p| grid.dequantize(grid.quantize(*p)))
            .collect(),
        normals: m
            .normals
            .iter()
            .map(|n| quantize::dequantize_normal(quantize::quantize_normal(*n)))
            .collect(),
        indices: m.indices.clone(),
    }
}

fn encode_v2(mesh: &Mesh, zstd: Option<i32>) -> Vec<u8> {
    MeshCodec::Meshopt { zstd }.encode(mesh).unwrap()
}

#[test]
fn meshes_come_back_quantised() {
    for zstd in [None, Some(3)] {
        for mesh in [crate::scene::bunny(), crate::lod::fixtures::building()] {
            let bytes = encode_v2(&mesh, zstd);
            let grid = Grid::around([&mesh]);
            let back = decode_mesh(&bytes, None).unwrap();
            assert_eq!(triangles(&back), triangles(&quantised(&mesh, &grid)));
            // Welded where quantising made two vertices one, never more.
            assert!(back.positions.len() <= mesh.positions.len());
            assert_eq!(grid_of(&bytes).unwrap(), grid);
        }
    }
}

#[test]
fn several_times_smaller_than_raw_floats() {
    // A scanned mesh's irregular vertices cost more than a building's.
    for (mesh, times) in [
        (crate::scene::bunny(), 2),
        (crate::lod::fixtures::building(), 3),
    ] {
        let raw = encode_mesh(&mesh).len();
        let plain = encode_v2(&mesh, None).len();
        let zstd = encode_v2(&mesh, Some(3)).len();
        assert!(plain * times < raw, "{plain} against {raw}");
        assert!(zstd <= plain, "{zstd} against {plain}");
    }
}

#[test]
fn empty_and_tiny_meshes() {
    let empty = Mesh {
        positions: vec![],
        normals: vec![],
        indices: vec![],
    };
    let back = decode_mesh(&encode_v2(&empty, Some(3)), None).unwrap();
    assert!(back.positions.is_empty() && back.indices.is_empty());
    let one = Mesh {
        positions: vec![[1.0, 2.0, 3.0], [2.0, 2.0, 3.0], [1.0, 3.0, 3.0]],
        normals: vec![[0.0, 0.0, 1.0]; 3],
        indices: vec![0, 1, 2],
    };
    let back = decode_mesh(&MeshCodec::default().encode(&one).unwrap(), None).unwrap();
    assert_eq!(
        triangles(&back),
        triangles(&one),
        "the box's corners are exact"
    );
}

#[test]
fn raw_meshes_still_read() {
    let bunny = crate::scene::bunny();
    let back = decode_mesh(&MeshCodec::Raw.encode(&bunny).unwrap(), None).unwrap();
    assert_eq!(
        (&back.positions, &back.indices),
        (&bunny.positions, &bunny.indices)
    );
}

#[test]
fn damage_is_an_error_never_a_panic() {
    let bunny = crate::scene::bunny();
    for zstd in [None, Some(3)] {
        let bytes = encode_v2(&bunny, zstd);
        for cut in [
            0,
            3,
            4,
            39,
            40,
            41,
            55,
            56,
            57,
            bytes.len() / 2,
            bytes.len() - 1,
        ] {
            assert!(decode_mesh(&bytes[..cut], None).is_err(), "cut at {cut}");
        }
        let mut rng = 0x2545_f491_4f6c_dd1du64;
        for _ in 0..2000 {
            let mut bad = bytes.clone();
            for _ in 0..3 {
                rng ^= rng << 13;
                rng ^= rng >> 7;
                rng ^= rng << 17;
                let at = 4 + (rng as usize) % (bad.len() - 4);
                bad[at] ^= 1 << (rng >> 60 & 7);
            }
            if let Ok(m) = decode_mesh(&bad, None) {
                // What decodes is still a mesh: indices in range, positions in its box.
                m.validate().unwrap();
                let grid = grid_of(&bad).unwrap();
                assert!(m
                    .positions
                    .iter()
                    .all(|p| (0..3).all(|k| p[k] >= grid.min[k] && p[k] <= grid.max[k])));
            }
        }
        // Counts that would make a reader allocate gigabytes are refused first: the
        // level's vertices (its table at byte 32), its index count (byte 48).
        for at in [32, 48] {
            let mut huge = bytes.clone();
            huge[at..at + 4].copy_from_slice(&(u32::MAX - 2).to_le_bytes());
            assert!(decode_mesh(&huge, None).is_err(), "{at}");
        }
    }
}

fn levels_of(mesh: &Mesh) -> Vec<Mesh> {
    let pm = crate::lod::ProgressiveMesh::build(mesh).unwrap();
    pm.levels(0.5, 20)
        .unwrap()
        .into_iter()
        .map(|l| l.mesh)
        .collect()
}

#[test]
fn levels_share_one_vertex_buffer_and_each_reads_a_prefix() {
    // A smooth mesh takes the vertex layout; a building's flat faces, the face layout,
    // whose coarse levels carry normals that are not their faces'.
    for (mesh, by_faces) in [
        (crate::scene::bunny(), false),
        (crate::lod::fixtures::building(), true),
    ] {
        for zstd in [None, Some(3)] {
            levels_round_trip(&mesh, Framing::of(zstd, None, Use::Levels), by_faces);
        }
    }
}

/// Dictionaries trained on the levels of the two test meshes, each level alone.
fn test_dictionaries() -> Dictionaries {
    let samples: Vec<Vec<u8>> = [crate::scene::bunny(), crate::lod::fixtures::building()]
        .iter()
        .flat_map(levels_of)
        .map(|l| geometry::encode(&l, Framing::Plain).unwrap())
        .collect();
    Dictionaries::train(&samples, &samples, 3)
}

#[test]
fn levels_compressed_with_a_dictionary_round_trip_and_need_it() {
    let dict = test_dictionaries();
    assert!(dict.has(Use::Levels) && dict.has(Use::Meshes), "{dict:?}");
    for (mesh, by_faces) in [
        (crate::scene::bunny(), false),
        (crate::lod::fixtures::building(), true),
    ] {
        levels_round_trip(&mesh, Framing::Dictionary(&dict, Use::Levels), by_faces);
        // Refused without the dictionary. (What it saves is a city's figure: a
        // dictionary trained on two meshes' levels saves nothing worth a test.)
        let levels = levels_of(&mesh);
        let coarsest_first: Vec<&Mesh> = levels.iter().rev().collect();
        let with =
            geometry::encode_levels(&coarsest_first, Framing::Dictionary(&dict, Use::Levels))
                .unwrap()
                .0;
        let e = geometry::decode_level(&with, 0, None).unwrap_err();
        assert!(e.contains("dictionary"), "{e}");
        let full = MeshCodec::meshopt()
            .encode_with(&mesh, Some(&dict))
            .unwrap();
        assert_eq!(
            decode_mesh(&full, Some(&dict)).unwrap(),
            decode_mesh(&MeshCodec::meshopt().encode(&mesh).unwrap(), None).unwrap()
        );
        assert!(MeshCodec::from_bytes(&full).is_err());
    }
}

fn levels_round_trip(mesh: &Mesh, framing: Framing, by_faces: bool) {
    let dict = match framing {
        Framing::Dictionary(d, _) => Some(d),
        _ => None,
    };
    {
        // Finest first, as the simplifier gives them; stored coarsest first.
        let finest_first = levels_of(mesh);
        assert!(finest_first.len() >= 3, "{} levels", finest_first.len());
        let levels: Vec<&Mesh> = finest_first.iter().rev().collect();
        let (blob, spans) = geometry::encode_levels(&levels, framing).unwrap();
        assert_eq!(geometry::by_faces(&blob), by_faces);
        let grid = Grid::around(levels.iter().copied());
        let mut previous = (0, 0);
        for (j, (mesh, span)) in levels.iter().zip(&spans).enumerate() {
            // The level's bytes and every coarser level's, and no more.
            let back = geometry::decode_level(&blob[..span.end], j, dict).unwrap();
            assert_eq!(
                triangles(&back),
                triangles(&quantised(mesh, &grid)),
                "level {j} of {} (faces {by_faces}, {framing:?})",
                levels.len()
            );
            assert_eq!(
                (back.positions.len(), back.indices.len()),
                (span.vertices, span.indices)
            );
            assert!(geometry::decode_level(&blob[..span.end - 1], j, dict).is_err());
            assert!(span.start == previous.0.max(geometry::head_len(levels.len())));
            // The vertex layout reads every coarser level's vertices; the face layout
            // builds only those its triangles use.
            assert!(by_faces || span.vertices >= previous.1);
            previous = (span.end, span.vertices);
        }
        assert_eq!(previous.0, blob.len());
        // The finest level's vertices are the full mesh's: none added by the coarser.
        assert!(spans.last().unwrap().vertices <= finest_first[0].positions.len());
        if dict.is_none() {
            assert_eq!(
                decode_mesh(&blob, None).unwrap(),
                geometry::decode_level(&blob, levels.len() - 1, None).unwrap()
            );
        }
        // Damaged bytes are an error or a mesh, never a panic.
        let mut rng = 0x9e37_79b9_7f4a_7c15u64;
        for _ in 0..500 {
            let mut bad = blob.clone();
            rng ^= rng << 13;
            rng ^= rng >> 7;
            rng ^= rng << 17;
            let at = 4 + (rng as usize) % (bad.len() - 4);
            bad[at] ^= 1 << (rng >> 60 & 7);
            for j in 0..levels.len() {
                if let Ok(m) = geometry::decode_level(&bad, j, dict) {
                    m.validate().unwrap();
                }
            }
        }
    }
}

#[test]
fn a_mesh_wider_than_an_f32_spans_is_refused_when_written() {
    // Finite positions whose box's span overflows: the reader refuses such a box, so
    // the writer must not write one.
    let mesh = Mesh {
        positions: vec![[-3e38, 0.0, 0.0], [3e38, 0.0, 0.0], [0.0, 1.0, 0.0]],
        normals: vec![[0.0, 0.0, 1.0]; 3],
        indices: vec![0, 1, 2],
    };
    mesh.validate().unwrap();
    let err = MeshCodec::meshopt().encode(&mesh).unwrap_err();
    assert!(err.contains("spans more than an f32"), "{err}");
}

#[test]
fn a_buffer_zstd_shrinks_past_what_a_reader_allows_is_written_unframed() {
    // The demo's city of 150 objects: one landmark's index buffer, 200,917 bytes, went
    // into a 131-byte frame with the city's dictionary, past the 1,024 times a reader
    // lets a buffer claim to expand, and the database could not read its own mesh.
    let dir = tempfile::tempdir().unwrap();
    let scene = dir.path().join("c.scene");
    let config = citygen::CityConfig {
        objects: 150,
        ..Default::default()
    };
    citygen::write_city(&config, &scene).unwrap();
    let path = dir.path().join("c.flaneur");
    let opts = crate::BuildOptions {
        codec: MeshCodec::meshopt(),
        ..Default::default()
    };
    crate::build_from_scene(&scene, &path, &opts).unwrap();
    let db = crate::Database::open(&path).unwrap();
    for o in db.range(&db.bounds()).unwrap().objects {
        let mesh = db
            .mesh(&o)
            .unwrap_or_else(|e| panic!("object {}: {e}", o.id));
        assert_eq!(mesh.triangle_count() as u32, o.triangles, "object {}", o.id);
    }
}
