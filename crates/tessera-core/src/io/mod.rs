//! Readers and writers of files.

pub mod export;
pub mod teaset;
