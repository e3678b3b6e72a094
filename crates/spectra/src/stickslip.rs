//! Stick-slip measures on recordings. (being written)
