//! An R-tree node's payload: `flaneur::fuzzing::rtree_node` says what it does with the bytes (README, "Fuzzing").

#![no_main]

libfuzzer_sys::fuzz_target!(|data: &[u8]| flaneur::fuzzing::rtree_node(data));
