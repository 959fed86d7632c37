//! An OBJ file through load_obj: `flaneur::fuzzing::obj` says what it does with the bytes (README, "Fuzzing").

#![no_main]

libfuzzer_sys::fuzz_target!(|data: &[u8]| flaneur::fuzzing::obj(data));
