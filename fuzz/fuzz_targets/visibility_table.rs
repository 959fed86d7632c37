//! The visibility table: head and every cell's record: `flaneur::fuzzing::visibility_table` says what it does with the bytes (README, "Fuzzing").

#![no_main]

libfuzzer_sys::fuzz_target!(|data: &[u8]| flaneur::fuzzing::visibility_table(data));
