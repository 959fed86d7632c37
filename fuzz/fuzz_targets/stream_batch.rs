//! The client's side against a hostile server: each input is the bytes a server sends,
//! read frame by frame as a client reads them (at most `MAX_TO_CLIENT` a frame) until
//! an error or the end. Any input must end in an error or the end, never a panic, and
//! nothing is reserved beyond the frame's bound.

#![no_main]

use flaneur_stream::protocol::{receive, MAX_TO_CLIENT};
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let mut input = data;
    while let Ok(Some(_)) = receive(&mut input, MAX_TO_CLIENT) {}
});
