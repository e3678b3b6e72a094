//! A 1-DOF torsional model driven by a measured top speed (the UFRJ LAVI rig page). Not written yet.
