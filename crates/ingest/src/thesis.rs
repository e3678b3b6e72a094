//! Thesis tables (data/thesis/*.csv) to typed data. Not written yet.
