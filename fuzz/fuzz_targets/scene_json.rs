//! Fuzz target: arbitrary bytes through luster's scene json loader.
#![no_main]
libfuzzer_sys::fuzz_target!(|data: &[u8]| luster_qa::fuzzing::Target::SceneJson.run(data));
