//! The HDoV-tree's head, a node, a V-page: `flaneur::fuzzing::hdov` says what it does with the bytes (README, "Fuzzing").

#![no_main]

libfuzzer_sys::fuzz_target!(|data: &[u8]| flaneur::fuzzing::hdov(data));
