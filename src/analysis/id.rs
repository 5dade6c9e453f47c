//! Stable node ids.
//!
//! An id names a node the same way across runs, machines and unrelated edits
//! of the file: it is a hash of the entry point's name, the node's source
//! text (whitespace collapsed) and which occurrence of that text in the
//! entry point it is. Line numbers and byte offsets are left out on purpose,
//! so adding a helper above the entry point leaves every id unchanged.

use std::hash::Hasher;

/// Collapses every run of whitespace to one space, so reflowing an
/// expression over lines does not change its id (what
/// [`write_normalized`] streams).
#[cfg(test)]
fn normalize(text: &str) -> String {
    text.split_whitespace().collect::<Vec<_>>().join(" ")
}

/// Feeds `hasher` the bytes of [`normalize`]`(text)` without building it:
/// the nodes of a long expression are prefixes of each other, and a copy
/// of each would make naming them quadratic in memory.
fn write_normalized(hasher: &mut impl Hasher, text: &str) {
    let mut started = false;
    let mut space = false;
    let mut word_start = None;
    for (i, c) in text.char_indices() {
        if c.is_whitespace() {
            if let Some(start) = word_start.take() {
                hasher.write(&text.as_bytes()[start..i]);
            }
            space = started;
        } else if word_start.is_none() {
            if space {
                hasher.write(b" ");
                space = false;
            }
            started = true;
            word_start = Some(i);
        }
    }
    if let Some(start) = word_start {
        hasher.write(&text.as_bytes()[start..]);
    }
}

/// A key equal for texts equal up to whitespace (what [`node_id`] counts
/// occurrences of), without keeping the text.
#[cfg(test)]
fn text_key(text: &str) -> u64 {
    let mut hasher = fnv::FnvHasher::default();
    write_normalized(&mut hasher, text);
    hasher.finish()
}

/// The id of the `occurrence`-th (0-based, in source order) node with text
/// `text` in entry point `entry`: `n` and eight hex digits.
pub fn node_id(entry: &str, text: &str, occurrence: usize) -> String {
    // FNV-1a is fixed by its specification, unlike std's SipHash keys or
    // `Hash` impls, so the same input hashes the same everywhere. It
    // hashes byte by byte, so feeding the normalized text in pieces hashes
    // it as a whole.
    let mut hasher = fnv::FnvHasher::default();
    hasher.write(entry.as_bytes());
    hasher.write(&[0]);
    write_normalized(&mut hasher, text);
    hasher.write(&[0]);
    hasher.write(&(occurrence as u64).to_le_bytes());
    let hash = hasher.finish();
    format!("n{:08x}", (hash ^ (hash >> 32)) as u32)
}

/// Ids and keys of nodes that start at the same byte, longest last,
/// hashed in one pass: the partial sums of `a + b + c + ...` are prefixes
/// of each other, and hashing each from its start is quadratic in the
/// length of the sum. FNV-1a hashes byte by byte, so hashing on from where
/// the previous node ended gives the same value as hashing anew.
pub struct PrefixHasher<'a> {
    text: &'a str,
    entry: &'a str,
    start: usize,
    at: usize,
    id: fnv::FnvHasher,
    key: fnv::FnvHasher,
    started: bool,
    space: bool,
}

impl<'a> PrefixHasher<'a> {
    pub fn new(text: &'a str, entry: &'a str) -> Self {
        let mut hasher = PrefixHasher {
            text,
            entry,
            start: usize::MAX,
            at: usize::MAX,
            id: fnv::FnvHasher::default(),
            key: fnv::FnvHasher::default(),
            started: false,
            space: false,
        };
        hasher.restart(0);
        hasher
    }

    fn restart(&mut self, start: usize) {
        self.start = start;
        self.at = start;
        self.id = fnv::FnvHasher::default();
        self.id.write(self.entry.as_bytes());
        self.id.write(&[0]);
        self.key = fnv::FnvHasher::default();
        self.started = false;
        self.space = false;
    }

    /// The [`text_key`] of `text[start..end]` and the state of the id's hash, which [`Self::id`]
    /// finishes, hashing on from the last node when it started at `start`
    /// and ended before `end`.
    pub fn node(&mut self, start: usize, end: usize) -> (u64, u64) {
        if start != self.start || end < self.at {
            self.restart(start);
        }
        for c in self.text[self.at..end].chars() {
            if c.is_whitespace() {
                self.space = self.started;
            } else {
                let mut bytes = [0; 4];
                let bytes = c.encode_utf8(&mut bytes).as_bytes();
                if self.space {
                    self.id.write(b" ");
                    self.key.write(b" ");
                    self.space = false;
                }
                self.id.write(bytes);
                self.key.write(bytes);
                self.started = true;
            }
        }
        self.at = end;
        (self.key.finish(), self.id.finish())
    }

    /// The id of a node whose text hashed to `state`, at `occurrence`: what
    /// [`node_id`] gives.
    pub fn id(state: u64, occurrence: usize) -> String {
        // FNV's state is its hash so far: hashing on from it.
        let mut state = fnv::FnvHasher::with_key(state);
        state.write(&[0]);
        state.write(&(occurrence as u64).to_le_bytes());
        let hash = state.finish();
        format!("n{:08x}", (hash ^ (hash >> 32)) as u32)
    }
}

/// How a node's text is shown (in reports, JSON and plans): whole up to
/// [`SHOWN`] characters, else its start and end around ` … `. Its span
/// still gives its whole extent; its id is of the whole text.
pub fn shown_text(text: &str) -> String {
    let count = text.chars().count();
    if count <= SHOWN {
        return text.to_string();
    }
    let head: String = text.chars().take(SHOWN * 2 / 3).collect();
    let tail: String = text.chars().skip(count - SHOWN / 3).collect();
    format!("{} … {}", head.trim_end(), tail.trim_start())
}

/// The most characters of a node's text shown whole.
pub const SHOWN: usize = 240;

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

    #[test]
    fn streamed_normalization_hashes_as_the_normalized_text() {
        for text in ["a + b", "  a  +\n\t b ", "x", "", " \n ", "f(a,\u{a0}b)  "] {
            let mut whole = fnv::FnvHasher::default();
            whole.write(normalize(text).as_bytes());
            assert_eq!(text_key(text), whole.finish(), "{text:?}");
        }
        assert_eq!(text_key("a  + b"), text_key("a +\nb"));
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
            let (key, state) = hasher.node(start, end);
            assert_eq!(key, text_key(&text[start..end]));
            assert_eq!(
                PrefixHasher::id(state, 1),
                node_id("fs_main", &text[start..end], 1)
            );
        }
        let (key, _) = hasher.node(start + 4, ends[2]);
        assert_eq!(key, text_key(&text[start + 4..ends[2]]));
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
