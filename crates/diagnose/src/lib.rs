//! Model vs measurement, candidate effects, selection by held-out misfit and information criterion.
