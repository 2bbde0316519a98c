#![no_main]
//! See fuzz/README.md and `ilopt_fuzz::props::check_toy_parser`.
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    ilopt_fuzz::props::check_toy_parser(data);
});
