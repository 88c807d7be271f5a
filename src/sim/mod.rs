//! Measurement simulator (under construction).
