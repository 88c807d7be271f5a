//! Summaries of TCP error sets (under construction).
