//! A campaign generator for tests only (truth model with hidden effects, sensor chain). Not written yet.
