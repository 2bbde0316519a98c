//! Which build of the kit wrote an output: its version and the git commit it was built from,
//! recorded in every file of `ilopt run` so that a number can be traced to the code that made it.

use serde::Serialize;

/// The kit's version and commit.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
pub struct Provenance {
    /// The package version (`CARGO_PKG_VERSION`).
    pub version: &'static str,
    /// The git commit the binary was built from (`git rev-parse HEAD` at build time; `unknown`
    /// when built outside a git checkout). Uncommitted changes are not marked.
    pub commit: &'static str,
}

/// This build's [`Provenance`].
pub const BUILD: Provenance = Provenance {
    version: env!("CARGO_PKG_VERSION"),
    commit: env!("ILOPT_GIT_COMMIT"),
};

impl Provenance {
    /// One line for a comment: `ilopt 0.1.0, commit 0123…`.
    pub fn line(&self) -> String {
        format!("ilopt {}, commit {}", self.version, self.commit)
    }
}
