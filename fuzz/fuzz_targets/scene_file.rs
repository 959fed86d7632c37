//! A scene file, streamed through SceneReader: `flaneur::fuzzing::scene_file` says what it does with the bytes (README, "Fuzzing").

#![no_main]

libfuzzer_sys::fuzz_target!(|data: &[u8]| flaneur::fuzzing::scene_file(data));
