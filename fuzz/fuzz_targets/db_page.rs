//! One data page's framing (kind, length, checksum), its payload to the decoder of its kind: `flaneur::fuzzing::db_page` says what it does with the bytes (README, "Fuzzing").

#![no_main]

libfuzzer_sys::fuzz_target!(|data: &[u8]| flaneur::fuzzing::db_page(data));
