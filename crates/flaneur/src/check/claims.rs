//! Which structure each page belongs to: the page scan (every page's kind, or why it is
//! damaged), the claims the structures make on pages as they are walked, and the
//! problems found on the way.

use std::collections::BTreeMap;

use super::{problem_of, Problem};
use crate::error::Error;
use crate::store::{Extent, PageKind, Store};

/// Pages the scan announces at once: as many as a remote store reads in one chunk, so
/// that its page cache (two chunks at the least) keeps them until they are read.
const SCAN_AHEAD: u64 = 256;

/// Pages, their kinds and their owners, and the problems found so far.
pub(super) struct Claims {
    /// Each page's kind; `None` for page 0 and for damaged pages.
    kinds: Vec<Option<PageKind>>,
    /// Each page's owner: an index into `parts` plus one; 0 for none.
    owners: Vec<u32>,
    parts: Vec<String>,
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
            parts: Vec::new(),
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

    /// `part` claims `extent`'s pages, which must be of `kind`; false (with the problem
    /// recorded) when the extent does not lie in the file.
    pub(super) fn claim_extent(&mut self, extent: &Extent, kind: PageKind, part: &str) -> bool {
        self.claim(extent.first_page, extent.page_count as u64, kind, part)
    }

    /// `part` claims pages `first..first + count`, which must be of `kind`; false (with
    /// the problem recorded) when they do not lie in the file.
    pub(super) fn claim(&mut self, first: u64, count: u64, kind: PageKind, part: &str) -> bool {
        let n = self.kinds.len() as u64;
        let end = first.saturating_add(count);
        if first == 0 || end > n {
            self.found(
                Some(first),
                part,
                format!("pages {first}..{end} do not lie among the file's data pages 1..{n}"),
            );
            return false;
        }
        self.parts.push(part.to_string());
        let owner = self.parts.len() as u32;
        for page in first..end {
            let i = page as usize;
            if let Some(found) = self.kinds[i].filter(|&k| k != kind) {
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
            match self.owners[i] {
                0 => self.owners[i] = owner,
                other => {
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
                    o => self.parts[o as usize - 1].clone(),
                },
                what: what.clone(),
            })
            .collect();
        out.extend(self.problems);
        out
    }
}
