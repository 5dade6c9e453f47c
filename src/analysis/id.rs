//! Stable node ids.
//!
//! An id names a node the same way across runs, machines and unrelated edits
//! of the file: it is a hash of the entry point's name, the node's source
//! text (whitespace collapsed) and which occurrence of that text in the
//! entry point it is. Line numbers and byte offsets are left out on purpose,
//! so adding a helper above the entry point leaves every id unchanged.

use std::hash::Hasher;

/// Collapses every run of whitespace to one space, so reflowing an
/// expression over lines does not change its id.
pub fn normalize(text: &str) -> String {
    text.split_whitespace().collect::<Vec<_>>().join(" ")
}

/// The id of the `occurrence`-th (0-based, in source order) node with text
/// `text` in entry point `entry`: `n` and eight hex digits.
pub fn node_id(entry: &str, text: &str, occurrence: usize) -> String {
    // FNV-1a is fixed by its specification, unlike std's SipHash keys or
    // `Hash` impls, so the same input hashes the same everywhere.
    let mut hasher = fnv::FnvHasher::default();
    hasher.write(entry.as_bytes());
    hasher.write(&[0]);
    hasher.write(normalize(text).as_bytes());
    hasher.write(&[0]);
    hasher.write(&(occurrence as u64).to_le_bytes());
    let hash = hasher.finish();
    format!("n{:08x}", (hash ^ (hash >> 32)) as u32)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ids_are_fixed_values() {
        // A change here renames every node users have written down.
        assert_eq!(
            node_id("fs_main", "a + b", 0),
            node_id("fs_main", "a  +\n b", 0)
        );
        assert_ne!(
            node_id("fs_main", "a + b", 0),
            node_id("fs_main", "a + b", 1)
        );
        assert_ne!(node_id("fs_main", "a + b", 0), node_id("fs", "a + b", 0));
        // FNV-1a 64 of "fs_main\0a + b\0" + 0u64 LE, folded to 32 bits;
        // computed independently of this code.
        assert_eq!(node_id("fs_main", "a + b", 0), "n8425b9ad");
    }
}
