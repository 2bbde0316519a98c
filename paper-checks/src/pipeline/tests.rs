//! The pipeline's keys, stale-file removal and theory cache.

use super::keys::theory_key;
use super::*;
use std::path::Path;

#[test]
fn the_theory_cache_key_names_the_size_profile_and_the_code() {
    let mut p = Profile::from_toml(
        &std::fs::read_to_string(Path::new(env!("CARGO_MANIFEST_DIR")).join("configs/quick.toml"))
            .expect("the quick profile"),
        Path::new("quick.toml"),
    )
    .expect("valid");
    let quick = theory_key(&p, "a");
    assert_eq!(quick, theory_key(&p, "a"));
    assert_ne!(quick, theory_key(&p, "b"));
    p.theory_profile = crate::config::TheorySize::Full;
    assert_ne!(quick, theory_key(&p, "a"));
}
