//! Fuzz target: arbitrary bytes through luster's image loader.
#![no_main]
libfuzzer_sys::fuzz_target!(|data: &[u8]| luster_qa::fuzzing::Target::Image.run(data));
