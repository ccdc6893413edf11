//! Fuzz target: arbitrary bytes through luster's shader loader.
#![no_main]
libfuzzer_sys::fuzz_target!(|data: &[u8]| luster_qa::fuzzing::Target::Shader.run(data));
