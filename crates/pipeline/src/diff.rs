//! `cargo xtask diff --baseline REV`: every table and figure series of the tree against a git revision, numerically. Not written yet.
