//! Force-sensor factor, static stiffness, log decrement, inertia; the thesis audit.
