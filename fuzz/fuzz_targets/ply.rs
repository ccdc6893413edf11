//! Fuzz target: arbitrary bytes through luster's ply loader.
#![no_main]
libfuzzer_sys::fuzz_target!(|data: &[u8]| luster::fuzzing::Target::Ply.run(data));
