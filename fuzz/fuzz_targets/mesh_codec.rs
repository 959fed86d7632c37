//! An object's mesh as its extent holds it: `flaneur::fuzzing::mesh_codec` says what it does with the bytes (README, "Fuzzing").

#![no_main]

libfuzzer_sys::fuzz_target!(|data: &[u8]| flaneur::fuzzing::mesh_codec(data));
