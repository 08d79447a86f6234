//! Reading and writing files: a located delimited-table reader, the tensile-test
//! reader, and atomic writes.

pub mod lcr;
pub mod manifest;
pub mod relaxation;
pub mod table;
pub mod tensile;
pub mod trace;
pub mod write;

use sha2::{Digest, Sha256};

/// Hex SHA-256 of bytes.
pub fn sha256_hex(bytes: &[u8]) -> String {
    Sha256::digest(bytes)
        .iter()
        .map(|b| format!("{b:02x}"))
        .collect()
}
