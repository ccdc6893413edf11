//! Fuzz target: arbitrary bytes as a part file on disk, through the reader
//! `luster merge` and `luster slurm status` use, and through both commands.
#![no_main]
libfuzzer_sys::fuzz_target!(|data: &[u8]| luster::cluster::partfile::fuzz(data));
