//! Moves into a viewcell, counted a frame at a time as every viewcell walk reports them:
//! a frame in a walkable cell other than the frame before's (outside every cell counts
//! as a cell of its own, so coming back in is a move).

/// The frames' cells seen so far, and the moves among them.
#[derive(Clone, Copy, Debug, Default)]
pub(crate) struct CellsEntered {
    /// The last frame's cell, once a frame has been seen.
    last: Option<Option<u32>>,
    entered: usize,
}

impl CellsEntered {
    /// The next frame's cell (`None` outside every one).
    pub(crate) fn add(&mut self, cell: Option<u32>) {
        if cell.is_some() && self.last.is_some_and(|last| last != cell) {
            self.entered += 1;
        }
        self.last = Some(cell);
    }

    /// Moves into a walkable cell so far.
    pub(crate) fn count(&self) -> usize {
        self.entered
    }
}
