//! Which build of the kit wrote an output: its version and the git commit it was built from,
//! recorded in every file of `ilopt run` so that a number can be traced to the code that made it.

use serde::Serialize;

/// The kit's version and commit.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
pub struct Provenance {
    /// The package version (`CARGO_PKG_VERSION`).
    pub version: &'static str,
    /// The git commit the binary was built from (`git rev-parse HEAD` at build time; `unknown`
    /// when built outside a git checkout).
    pub commit: &'static str,
    /// Whether tracked files differed from `commit` when the binary was built (`git status
    /// --porcelain`), so that the commit alone does not name the code; `None` when unknown.
    pub uncommitted_changes: Option<bool>,
}

/// `ILOPT_GIT_DIRTY`'s value as a flag: `true`, `false`, anything else unknown.
const fn flag(text: &str) -> Option<bool> {
    match text.as_bytes() {
        b"true" => Some(true),
        b"false" => Some(false),
        _ => None,
    }
}

/// This build's [`Provenance`].
pub const BUILD: Provenance = Provenance {
    version: env!("CARGO_PKG_VERSION"),
    commit: env!("ILOPT_GIT_COMMIT"),
    uncommitted_changes: flag(env!("ILOPT_GIT_DIRTY")),
};

impl Provenance {
    /// One line for a comment: `ilopt 0.1.0, commit 0123…`, with `, with uncommitted changes`
    /// when the build had them.
    pub fn line(&self) -> String {
        let changes = match self.uncommitted_changes {
            Some(true) => ", with uncommitted changes",
            Some(false) | None => "",
        };
        format!("ilopt {}, commit {}{changes}", self.version, self.commit)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_flag_reads_true_false_and_nothing_else() {
        assert_eq!(flag("true"), Some(true));
        assert_eq!(flag("false"), Some(false));
        assert_eq!(flag("unknown"), None);
        assert_eq!(flag(""), None);
    }

    #[test]
    fn the_line_marks_uncommitted_changes_only_when_there_were_some() {
        let build = |uncommitted_changes| Provenance {
            version: "0.1.0",
            commit: "abc",
            uncommitted_changes,
        };
        assert_eq!(build(Some(false)).line(), "ilopt 0.1.0, commit abc");
        assert_eq!(build(None).line(), "ilopt 0.1.0, commit abc");
        assert_eq!(
            build(Some(true)).line(),
            "ilopt 0.1.0, commit abc, with uncommitted changes"
        );
    }
}
