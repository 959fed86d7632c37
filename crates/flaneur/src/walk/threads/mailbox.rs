//! Where a never-wait walk's viewer leaves its latest position for a loader thread:
//! the loader takes the newest when it is free (older ones are not worth looking from),
//! sleeps while there is none, and learns of the walk's end.

use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
use std::sync::{Condvar, Mutex};
use std::time::Duration;

/// The viewer's latest post, for a loader to take when it is free, and the walk's end.
pub(crate) struct Mailbox<T> {
    latest: Mutex<Option<T>>,
    wake: Condvar,
    /// The viewer's latest frame: the clock a loader's answers are delivered at.
    now: AtomicU64,
    ended: AtomicBool,
}

impl<T> Default for Mailbox<T> {
    fn default() -> Mailbox<T> {
        Mailbox {
            latest: Mutex::new(None),
            wake: Condvar::new(),
            now: AtomicU64::new(0),
            ended: AtomicBool::new(false),
        }
    }
}

/// How long an idle loader sleeps between looks at the walk's end.
const IDLE_WAKE: Duration = Duration::from_millis(50);

impl<T> Mailbox<T> {
    /// Leaves `post`, the viewer's at frame `frame`, in place of any not yet taken.
    pub fn post(&self, frame: u64, post: T) {
        self.now.store(frame, Ordering::Relaxed);
        if let Ok(mut latest) = self.latest.lock() {
            *latest = Some(post);
        }
        self.wake.notify_one();
    }

    pub fn end(&self) {
        self.ended.store(true, Ordering::Relaxed);
        self.wake.notify_one();
    }

    pub fn ended(&self) -> bool {
        self.ended.load(Ordering::Relaxed)
    }

    pub fn now(&self) -> u64 {
        self.now.load(Ordering::Relaxed)
    }

    /// The latest post since the last take; with `block`, waits for one (or the walk's
    /// end).
    pub fn take(&self, block: bool) -> Option<T> {
        let mut latest = self.latest.lock().ok()?;
        while block && latest.is_none() && !self.ended() {
            latest = self.wake.wait_timeout(latest, IDLE_WAKE).ok()?.0;
        }
        latest.take()
    }
}
