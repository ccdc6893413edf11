//! Fuzz target: arbitrary bytes through luster's obj loader.
#![no_main]
libfuzzer_sys::fuzz_target!(|data: &[u8]| luster_qa::fuzzing::Target::Obj.run(data));
