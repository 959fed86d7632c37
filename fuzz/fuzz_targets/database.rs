//! A whole database file, opened and queried: `flaneur::fuzzing::database` says what it does with the bytes (README, "Fuzzing").

#![no_main]

libfuzzer_sys::fuzz_target!(|data: &[u8]| flaneur::fuzzing::database(data));
