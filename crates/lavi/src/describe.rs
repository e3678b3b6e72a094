//! Description (stub).
