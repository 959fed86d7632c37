//! An OpenStreetMap PBF extract through the import: `flaneur::fuzzing::osm_pbf` says what it does with the bytes (README, "Fuzzing").

#![no_main]

libfuzzer_sys::fuzz_target!(|data: &[u8]| flaneur::fuzzing::osm_pbf(data));
