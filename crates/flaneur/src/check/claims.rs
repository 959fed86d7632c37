//! Which structure each page belongs to: the page scan (every page's kind, or why it is
//! damaged), the claims the structures make on pages as they are walked, and the
//! problems found on the way.
//!
//! A page belongs either whole to one structure, or, when packed extents share it, to
//! several by byte ranges that must not overlap: a page claimed both ways, or two
//! packed blobs over the same bytes, is a problem, as two whole claims are.

use std::collections::{BTreeMap, HashMap};

use super::{problem_of, Problem};
use crate::error::Error;
use crate::store::{Extent, PageKind, Store};

/// The owner of a page that packed extents share: its owners are in `Claims::shared`.
const SHARED: u32 = u32::MAX;

/// Pages the scan announces at once: as many as a remote store reads in one chunk, so
/// that its page cache (two chunks at the least) keeps them until they are read.
const SCAN_AHEAD: u64 = 256;

/// Pages, their kinds and their owners, and the problems found so far.
pub(super) struct Claims {
    /// Each page's kind; `None` for page 0 and for damaged pages.
    kinds: Vec<Option<PageKind>>,
    /// Each page's owner: an index into `parts` plus one; 0 for none; `SHARED` for a
    /// page packed extents share.
    owners: Vec<u32>,
    /// The byte ranges of each shared page that packed extents claim, sorted by start:
    /// (start, end, owner as in `owners`).
    shared: HashMap<u64, Vec<(usize, usize, u32)>>,
    parts: Vec<String>,
    /// Payload bytes per page, to place packed extents' bytes in their pages.
    payload_size: usize,
    /// Pages the scan found damaged, and why: reported once, with their owner.
    damaged: BTreeMap<u64, String>,
    /// Pages of each kind the header counts.
    counted: Vec<(PageKind, u64)>,
    problems: Vec<Problem>,
}

impl Claims {
    /// Reads every data page of `store` once, verifying its framing and checksum.
    pub(super) fn scan(store: &Store) -> Claims {
        let n = store.page_count() as usize;
        let mut c = Claims {
            kinds: vec![None; n],
            owners: vec![0; n],
            shared: HashMap::new(),
            parts: Vec::new(),
            payload_size: store.payload_size(),
            damaged: BTreeMap::new(),
            counted: Vec::new(),
            problems: Vec::new(),
        };
        for page in 1..n as u64 {
            if (page - 1).is_multiple_of(SCAN_AHEAD) {
                // A remote store fetches the next pages in one request, not one each.
                let ahead: Vec<u64> = (page..(page + SCAN_AHEAD).min(n as u64)).collect();
                store.announce(&ahead);
            }
            match store.read_any_page(page) {
                Ok((kind, _)) => c.kinds[page as usize] = Some(kind),
                Err(Error::CorruptPage { what, .. }) => {
                    c.damaged.insert(page, what);
                }
                Err(e) => {
                    c.damaged.insert(page, e.to_string());
                }
            }
        }
        c
    }

    /// Records `e` as a problem of `part`, unless it is about a page the scan already
    /// found damaged (reported once, with its owner).
    pub(super) fn problem(&mut self, e: &Error, part: &str) {
        if let Error::CorruptPage { page, .. } = e {
            if self.damaged.contains_key(page) {
                return;
            }
        }
        self.problems.push(problem_of(e, part));
    }

    /// Records a problem of `part` found on `page`.
    pub(super) fn found(&mut self, page: Option<u64>, part: &str, what: String) {
        self.problems.push(Problem {
            page,
            part: part.to_string(),
            what,
        });
    }

    /// `part` claims `extent`'s pages, which must be of `kind`: a whole extent its pages
    /// whole, a packed one its bytes in them. False (with the problem recorded) when the
    /// extent does not lie in the file, or a packed one's offset and page count do not
    /// fit its length.
    pub(super) fn claim_extent(&mut self, extent: &Extent, kind: PageKind, part: &str) -> bool {
        if !extent.packed {
            return self.claim(extent.first_page, extent.page_count as u64, kind, part);
        }
        let payload = self.payload_size;
        let (offset, len) = (extent.offset as usize, extent.byte_len as usize);
        if let Some(what) = extent.shape_problem(payload) {
            self.found(Some(extent.first_page), part, what);
            return false;
        }
        let (first, count) = (extent.first_page, extent.page_count as u64);
        let Some(owner) = self.claim_pages(first, count, kind, part) else {
            return false;
        };
        let end_in_run = offset + len;
        for (i, page) in (first..first + count).enumerate() {
            let start = if i == 0 { offset } else { 0 };
            let end = (end_in_run - i * payload).min(payload);
            self.claim_bytes(page, start, end, owner, part);
        }
        true
    }

    /// Bytes `start..end` of `page` go to `owner`, a packed extent of `part`.
    fn claim_bytes(&mut self, page: u64, start: usize, end: usize, owner: u32, part: &str) {
        let i = page as usize;
        let other = match self.owners[i] {
            0 => {
                self.owners[i] = SHARED;
                self.shared.insert(page, vec![(start, end, owner)]);
                return;
            }
            SHARED => {
                let ranges = self.shared.entry(page).or_default();
                let at = ranges.partition_point(|r| r.0 < start);
                let before = at.checked_sub(1).map(|j| ranges[j]);
                let clash = before
                    .filter(|r| r.1 > start)
                    .or_else(|| ranges.get(at).copied().filter(|r| r.0 < end));
                match clash {
                    None => {
                        ranges.insert(at, (start, end, owner));
                        return;
                    }
                    Some(r) => r.2,
                }
            }
            whole => whole,
        };
        let first_owner = self.parts[other as usize - 1].clone();
        self.found(
            Some(page),
            part,
            format!("the page also belongs to {first_owner} (over bytes {start}..{end})"),
        );
    }

    /// `part` claims pages `first..first + count`, which must be of `kind`; false (with
    /// the problem recorded) when they do not lie in the file.
    pub(super) fn claim(&mut self, first: u64, count: u64, kind: PageKind, part: &str) -> bool {
        let Some(owner) = self.claim_pages(first, count, kind, part) else {
            return false;
        };
        for page in first..first + count {
            let i = page as usize;
            match self.owners[i] {
                0 => self.owners[i] = owner,
                other => {
                    let other = match other {
                        SHARED => self.shared[&page][0].2,
                        o => o,
                    };
                    let first_owner = self.parts[other as usize - 1].clone();
                    self.found(
                        Some(page),
                        part,
                        format!("the page also belongs to {first_owner}"),
                    );
                }
            }
        }
        true
    }

    /// Checks that pages `first..first + count` lie in the file and are of `kind`, and
    /// registers `part` as an owner: its number, or `None` (with the problem recorded)
    /// when the pages do not lie in the file.
    fn claim_pages(&mut self, first: u64, count: u64, kind: PageKind, part: &str) -> Option<u32> {
        let n = self.kinds.len() as u64;
        let end = first.saturating_add(count);
        if first == 0 || end > n {
            self.found(
                Some(first),
                part,
                format!("pages {first}..{end} do not lie among the file's data pages 1..{n}"),
            );
            return None;
        }
        self.parts.push(part.to_string());
        for page in first..end {
            if let Some(found) = self.kinds[page as usize].filter(|&k| k != kind) {
                self.found(
                    Some(page),
                    part,
                    format!(
                        "a {} page where a {} page belongs",
                        found.name(),
                        kind.name()
                    ),
                );
            }
        }
        Some(self.parts.len() as u32)
    }

    /// The header counts `pages` pages of `kind`.
    pub(super) fn count_kind(&mut self, kind: PageKind, pages: u64) {
        match self.counted.iter_mut().find(|(k, _)| *k == kind) {
            Some((_, n)) => *n += pages,
            None => self.counted.push((kind, pages)),
        }
    }

    /// Compares the header's counts of pages by kind with the pages the scan found.
    pub(super) fn check_kind_counts(&mut self) {
        for (kind, counted) in self.counted.clone() {
            let found = self.kinds.iter().filter(|k| **k == Some(kind)).count() as u64;
            let damaged = self.damaged.len() as u64;
            // A damaged page's kind is unknown: it may be one of the missing ones.
            if found > counted || found + damaged < counted {
                self.found(
                    None,
                    "the file header",
                    format!(
                        "it counts {counted} {} pages, the file holds {found}",
                        kind.name()
                    ),
                );
            }
        }
    }

    /// Pages of each kind no structure claimed, by kind name.
    pub(super) fn unclaimed(&self) -> Vec<(String, u64)> {
        let mut by_kind: BTreeMap<&'static str, u64> = BTreeMap::new();
        for (kind, owner) in self.kinds.iter().zip(&self.owners) {
            if let (Some(k), 0) = (kind, owner) {
                *by_kind.entry(k.name()).or_default() += 1;
            }
        }
        by_kind
            .into_iter()
            .map(|(k, n)| (k.to_string(), n))
            .collect()
    }

    /// Every problem: the damaged pages first, each named with its owner, then the
    /// structures' problems in the order found.
    pub(super) fn into_problems(self) -> Vec<Problem> {
        let mut out: Vec<Problem> = self
            .damaged
            .iter()
            .map(|(&page, what)| Problem {
                page: Some(page),
                part: match self.owners[page as usize] {
                    0 => "no structure (a page nothing claims)".to_string(),
                    SHARED => self.shared[&page]
                        .iter()
                        .map(|r| self.parts[r.2 as usize - 1].as_str())
                        .collect::<Vec<_>>()
                        .join(", "),
                    o => self.parts[o as usize - 1].clone(),
                },
                what: what.clone(),
            })
            .collect();
        out.extend(self.problems);
        out
    }
}
