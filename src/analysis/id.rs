//! Stable node ids.
//!
//! An id names a node the same way across runs, machines and unrelated edits
//! of the file: it is a hash of the entry point's name, the node's source
//! text (whitespace collapsed) and which occurrence of that text in the
//! entry point it is. Line numbers and byte offsets are left out on purpose,
//! so adding a helper above the entry point leaves every id unchanged.

use std::hash::Hasher;

/// The id of the `occurrence`-th (0-based, in source order) node with text
/// `text` in entry point `entry`: `n` and eight hex digits.
pub fn node_id(entry: &str, text: &str, occurrence: usize) -> String {
    let state = PrefixHasher::new(text, entry).node(0, text.len());
    PrefixHasher::id(state, occurrence)
}

/// Hashes node texts for their ids: FNV-1a (fixed by its specification,
/// unlike std's SipHash keys or `Hash` impls, so the same input hashes
/// the same everywhere) of the entry point's name, a zero byte, the text
/// with every run of whitespace collapsed to one space (reflowing an
/// expression over lines keeps its id), a zero byte and the occurrence.
///
/// Nodes that start at the same byte are hashed in one pass, longest last:
/// the partial sums of `a + b + c + ...` are prefixes of each other, and
/// hashing each from its start is quadratic in the length of the sum.
/// FNV-1a hashes byte by byte, so hashing on from where the previous node
/// ended gives the same value as hashing anew.
pub struct PrefixHasher<'a> {
    text: &'a str,
    entry: &'a str,
    start: usize,
    at: usize,
    hasher: fnv::FnvHasher,
    /// Whether a non-space has been hashed, and whether a space is owed
    /// before the next one (trailing spaces are not part of the text).
    started: bool,
    space: bool,
}

impl<'a> PrefixHasher<'a> {
    pub fn new(text: &'a str, entry: &'a str) -> Self {
        let mut hasher = PrefixHasher {
            text,
            entry,
            start: 0,
            at: 0,
            hasher: fnv::FnvHasher::default(),
            started: false,
            space: false,
        };
        hasher.restart(0);
        hasher
    }

    fn restart(&mut self, start: usize) {
        self.start = start;
        self.at = start;
        self.hasher = fnv::FnvHasher::default();
        self.hasher.write(self.entry.as_bytes());
        self.hasher.write(&[0]);
        self.started = false;
        self.space = false;
    }

    /// The hash so far of `text[start..end]`, which [`Self::id`] finishes;
    /// equal for texts equal up to whitespace (what occurrences count).
    /// Hashes on from the last node when it started at `start` and ended
    /// before `end`.
    pub fn node(&mut self, start: usize, end: usize) -> u64 {
        if start != self.start || end < self.at {
            self.restart(start);
        }
        for c in self.text[self.at..end].chars() {
            if c.is_whitespace() {
                self.space = self.started;
            } else {
                if self.space {
                    self.hasher.write(b" ");
                    self.space = false;
                }
                self.hasher.write(c.encode_utf8(&mut [0; 4]).as_bytes());
                self.started = true;
            }
        }
        self.at = end;
        self.hasher.finish()
    }

    /// The id of a node whose text hashed to `state`, at `occurrence`.
    pub fn id(state: u64, occurrence: usize) -> String {
        // FNV's state is its hash so far: hashing on from it.
        let mut hasher = fnv::FnvHasher::with_key(state);
        hasher.write(&[0]);
        hasher.write(&(occurrence as u64).to_le_bytes());
        let hash = hasher.finish();
        format!("n{:08x}", (hash ^ (hash >> 32)) as u32)
    }
}

/// How a node's text is shown (in reports, JSON and plans): whole up to
/// [`SHOWN`] characters, else its start and end around ` … `. Its span
/// still gives its whole extent; its id is of the whole text.
pub fn shown_text(text: &str) -> String {
    // Only the ends are read: a long sum's nested partial sums are texts
    // as long as the sum, and counting each one's characters would make
    // naming the nodes quadratic.
    let short = text.len() <= SHOWN || text.chars().nth(SHOWN).is_none();
    if short {
        return text.to_string();
    }
    let head_end = text
        .char_indices()
        .nth(SHOWN * 2 / 3)
        .map_or(text.len(), |(at, _)| at);
    let tail_start = text
        .char_indices()
        .rev()
        .nth(SHOWN / 3 - 1)
        .map_or(0, |(at, _)| at);
    format!(
        "{} … {}",
        text[..head_end].trim_end(),
        text[tail_start..].trim_start()
    )
}

/// The most characters of a node's text shown whole.
pub const SHOWN: usize = 240;

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn long_texts_keep_their_ends() {
        let text: String = (0..100).map(|i| format!("é{i} + ")).collect::<String>() + "z";
        let shown = shown_text(&text);
        let chars: Vec<char> = text.chars().collect();
        let head: String = chars[..SHOWN * 2 / 3].iter().collect();
        let tail: String = chars[chars.len() - SHOWN / 3..].iter().collect();
        assert_eq!(
            shown,
            format!("{} … {}", head.trim_end(), tail.trim_start())
        );
        assert_eq!(shown_text("a + b"), "a + b");
        let exactly: String = "é".repeat(SHOWN);
        assert_eq!(shown_text(&exactly), exactly);
    }

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

    /// The id as its definition states it, hashing the collapsed text in
    /// one piece.
    fn reference_id(entry: &str, text: &str, occurrence: usize) -> String {
        let normalized = text.split_whitespace().collect::<Vec<_>>().join(" ");
        let mut hasher = fnv::FnvHasher::default();
        hasher.write(entry.as_bytes());
        hasher.write(&[0]);
        hasher.write(normalized.as_bytes());
        hasher.write(&[0]);
        hasher.write(&(occurrence as u64).to_le_bytes());
        let hash = hasher.finish();
        format!("n{:08x}", (hash ^ (hash >> 32)) as u32)
    }

    #[test]
    fn streamed_normalization_hashes_as_the_normalized_text() {
        for text in ["a + b", "  a  +\n\t b ", "x", "", " \n ", "f(a,\u{a0}b)  "] {
            assert_eq!(
                node_id("fs", text, 2),
                reference_id("fs", text, 2),
                "{text:?}"
            );
        }
    }

    #[test]
    fn hashing_on_from_a_prefix_gives_the_ids_hashed_anew() {
        let text = "let s = a +  b\n  + c + d;";
        let start = text.find('a').unwrap();
        let mut hasher = PrefixHasher::new(text, "fs_main");
        let ends: Vec<usize> = ["b", "c", "d"]
            .iter()
            .map(|w| text.find(w).unwrap() + 1)
            .collect();
        // In order, out of order (a restart), and from another start.
        for &end in ends.iter().chain(&[ends[0], ends[2]]) {
            let state = hasher.node(start, end);
            assert_eq!(
                PrefixHasher::id(state, 1),
                reference_id("fs_main", &text[start..end], 1)
            );
        }
        let state = hasher.node(start + 4, ends[2]);
        assert_eq!(
            PrefixHasher::id(state, 0),
            reference_id("fs_main", &text[start + 4..ends[2]], 0)
        );
    }

    #[test]
    fn long_texts_are_shown_elided() {
        let long = "sin(p.x) + ".repeat(100);
        let shown = shown_text(&long);
        assert!(shown.chars().count() < SHOWN + 4, "{shown}");
        assert!(shown.starts_with("sin(p.x) + sin") && shown.contains(" … "));
        assert_eq!(shown_text("a + b"), "a + b");
    }
}
