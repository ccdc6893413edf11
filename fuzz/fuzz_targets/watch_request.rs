//! Fuzz target: arbitrary bytes through `luster watch`'s request parser, read
//! as a connection reads them (a head, its body, the next head).
#![no_main]
libfuzzer_sys::fuzz_target!(|data: &[u8]| luster::watch::request::fuzz(data));
