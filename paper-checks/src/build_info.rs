//! What this binary was built from (recorded by the package's build script): the hash of the
//! sources that can change a number in the appendix, and the git commit at build time.

/// FNV-1a (64 bit, hex) over the kit's, `theory/`'s and this package's sources, manifests,
/// lock file, profiles, toy examples and experts. Every cached result is keyed by it.
pub const SOURCE_HASH: &str = env!("PAPER_CHECKS_SOURCE_HASH");

/// `git rev-parse HEAD` of the checkout the binary was built from (`unknown` outside git).
pub const GIT_COMMIT: &str = env!("PAPER_CHECKS_GIT_COMMIT");

/// Whether tracked files differed from that commit at build time (`true`, `false` or
/// `unknown`).
pub const GIT_DIRTY: &str = env!("PAPER_CHECKS_GIT_DIRTY");
