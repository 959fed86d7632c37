//! The LOD table: head, fence, entry pages: `flaneur::fuzzing::lod_table` says what it does with the bytes (README, "Fuzzing").

#![no_main]

libfuzzer_sys::fuzz_target!(|data: &[u8]| flaneur::fuzzing::lod_table(data));
