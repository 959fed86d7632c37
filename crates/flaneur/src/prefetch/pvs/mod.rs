//! Neighbour PVS prefetching for client–server walkthroughs (Zheng 2007, chapter 7).
//!
//! The server holds a PVS per viewcell of a uniform grid; the client keeps the PVS
//! rows and objects of at most nine viewcells and, as the viewer moves, prefetches
//! those of the neighbours it may enter next. SNP (`snp`, §7.2.1) fetches all eight
//! neighbours on every cell change; PBNP (`pbnp`, §7.2.2) fetches only those the
//! viewer leans towards, read from which of nine regions of its cell it stands in
//! (h(R), Table 7.1); LANP (`lanp`, ours) fetches every cell the viewer may reach
//! before an answer asked now arrives, as far as the measured round trip and speed
//! take it, and lets the cache grow to hold them. All send only what the client lacks
//! (`delta`, §7.3) and share one cache and replacement rule (`cache`, §7.4); `client`
//! runs one position's transaction. `stored` reads a database's precomputed visibility as the server's
//! table; `prefetch::pvs::routes` draws the thesis's two routes. The simulation of §7.5
//! (a whole route's counts), the thesis's synthetic city and its in-memory PVS table
//! are the `pvs-prefetch` experiment's, in `flaneur-bench`.
//!
//! Choices the thesis leaves open, and ours:
//!
//! - **Region size** (PBNP): the side and corner regions are bands a fraction
//!   `border` of the cell's side wide, default 0.25 ([`DEFAULT_BORDER`]): 5 m bands and
//!   a 10 m middle on 20 m cells. A band at least one step wide means a walker cannot
//!   step from the middle into the next cell unannounced; `flaneur bench pvs-prefetch`
//!   sweeps it. Settings in (0, 0.5]; at 0.5 there is no middle region.
//! - **Cache swap**: one per cell evicted from the cache (its PVS row and the objects
//!   no kept cell sees); a cell admitted into free room is no swap.
//! - **Replacement**: entries go only when the 9-entry table is full, only as many as
//!   the new cells need, and only cells with Dr > 1 or Dc > 1 from the current one;
//!   among those, the farthest first, then the least recently needed, then the lowest
//!   (row, column) — deterministic.
//! - **Transactions**: one whenever the area at a position holds a cell not cached,
//!   even if every object it sees is already held (its row is still sent). The start-up
//!   transaction counts, and its objects count in the objects per transaction; it is
//!   also reported apart, as the thesis does. The thesis counts transactions, it does
//!   not time them: [`PvsClient::step`] completes one at once, [`PvsClient::look`] and
//!   [`PvsClient::deliver`] let its answer come later (the table changes on asking,
//!   the objects are on hand on the answer).
//! - **Delta-transmission**: S_I is everything the client holds when it asks; an
//!   object that a new cell and an evicted one both see is kept, not dropped and sent
//!   again.
//! - **Cells without a viewcell** (inside buildings, off the grid) are never requested
//!   nor cached; a position in one is an error, as is a position that is not finite or
//!   lies outside the grid.
//! - **Visual misses**: at each position after the start, the objects of the current
//!   cell's PVS not on hand before that position's transaction. With answers at once
//!   they arise only on entering a cell (none for SNP, whose area always holds every
//!   neighbour).
//! - **When the client looks**: once per position of the route, i.e. per step (the
//!   thesis checks before every frame; between steps the position does not change).
//! - **Cache size**: 9 entries as in the thesis; it may be set larger, never smaller,
//!   since the current cell and its eight neighbours must fit. LANP's grows to its
//!   area when that is larger (`PrefetchArea::grows_cache`).
//! - **Orientation**: columns grow east (+x), rows south (+z); (a − 1, b + 1) is
//!   north-east of (a, b), as in Fig. 7.1.
//! - **The routes**: see [`routes`](crate::prefetch::pvs::routes); the synthetic table is
//!   described with the experiment that draws it.

mod area;
mod cache;
mod client;
mod delta;
mod grid;
mod lanp;
mod pbnp;
pub mod routes;
mod snp;
mod source;
mod stored;

pub use area::{Area, Observed, PrefetchArea};
pub use cache::{Admitted, ClientCache, THESIS_CAPACITY};
pub use client::{PvsClient, StepOutcome, Transaction};
pub use grid::{check_border, Cell, Position, Region, ViewcellGrid, DEFAULT_BORDER};
pub use lanp::Lanp;
pub use pbnp::Pbnp;
pub use snp::Snp;
pub use source::{ObjectId, PvsSource};
pub use stored::StoredPvs;
