//! Taking a prefetch thread's answer when there is one, as the REVIEW and VISUAL modes
//! both do: one already there, or one that comes within a wait.

use std::sync::mpsc;
use std::time::Duration;

use crate::error::{Error, Result};

/// The next answer on `rx`: without `wait`, only one already there; with it, one that
/// comes within that long. `None` when none came; an error when the thread stopped.
pub(crate) fn receive<T>(rx: &mpsc::Receiver<T>, wait: Option<Duration>) -> Result<Option<T>> {
    let stopped = || Error::Invalid("the prefetch thread stopped".into());
    match wait {
        Some(limit) => match rx.recv_timeout(limit) {
            Ok(r) => Ok(Some(r)),
            Err(mpsc::RecvTimeoutError::Timeout) => Ok(None),
            Err(mpsc::RecvTimeoutError::Disconnected) => Err(stopped()),
        },
        None => match rx.try_recv() {
            Ok(r) => Ok(Some(r)),
            Err(mpsc::TryRecvError::Empty) => Ok(None),
            Err(mpsc::TryRecvError::Disconnected) => Err(stopped()),
        },
    }
}
