//! Test helpers: run stages into a temporary out dir and snapshot their outputs. Not written yet.
