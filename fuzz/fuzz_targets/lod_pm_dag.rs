//! An object's progressive mesh and DAG, checked against each other: `flaneur::fuzzing::lod_pm_dag` says what it does with the bytes (README, "Fuzzing").

#![no_main]

libfuzzer_sys::fuzz_target!(|data: &[u8]| flaneur::fuzzing::lod_pm_dag(data));
