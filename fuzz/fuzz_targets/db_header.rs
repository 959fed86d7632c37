//! The database file's header page and segment table: `flaneur::fuzzing::db_header` says what it does with the bytes (README, "Fuzzing").

#![no_main]

libfuzzer_sys::fuzz_target!(|data: &[u8]| flaneur::fuzzing::db_header(data));
