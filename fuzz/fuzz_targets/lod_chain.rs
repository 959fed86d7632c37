//! An object's LOD chain: directory and levels: `flaneur::fuzzing::lod_chain` says what it does with the bytes (README, "Fuzzing").

#![no_main]

libfuzzer_sys::fuzz_target!(|data: &[u8]| flaneur::fuzzing::lod_chain(data));
