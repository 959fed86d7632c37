//! A glTF file (JSON or GLB) through the import: `flaneur::fuzzing::gltf` says what it does with the bytes (README, "Fuzzing").

#![no_main]

libfuzzer_sys::fuzz_target!(|data: &[u8]| flaneur::fuzzing::gltf(data));
