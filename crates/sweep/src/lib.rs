//! Severity maps and bifurcation diagrams over the rig model, up and down, rayon, deterministic order.
