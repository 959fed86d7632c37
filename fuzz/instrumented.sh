#!/bin/sh
# Runs a command (a `cargo +nightly fuzz` one) with the C and C++ that crates compile
# through the `cc` crate instrumented as cargo fuzz instruments Rust: libFuzzer's
# coverage (-fsanitize=fuzzer-no-link) and AddressSanitizer. That C and C++ includes
# decoders of untrusted bytes: meshoptimizer's vertex and index codecs (the meshopt
# crate) and zstd (zstd-sys), which format version 2 reads meshes with. Without it the
# fuzzer sees none of their branches and ASan none of their reads. Needs clang (gcc
# cannot emit libFuzzer's coverage). From fuzz/:
#
#   ./instrumented.sh cargo +nightly fuzz run mesh_codec -- -runs=10000000
#
# Changing these flags rebuilds every crate that uses cc (cc tells cargo to).
set -eu
here=$(cd "$(dirname "$0")" && pwd)
flags="-fsanitize=fuzzer-no-link,address -fsanitize-coverage-ignorelist=$here/not-instrumented.txt -fsanitize-ignorelist=$here/not-instrumented.txt"
export CC=clang CXX=clang++ CFLAGS="$flags" CXXFLAGS="$flags"
exec "$@"
