//! The open connections: admission under the cap, eviction of the longest idle one, and
//! the stop of all at shutdown.

use std::collections::BTreeMap;
use std::sync::{Arc, Mutex, MutexGuard, PoisonError};

use super::activity::Activity;
use crate::server::metrics::Metrics;

/// Every open connection, by the order it was accepted in.
#[derive(Debug)]
pub(super) struct Table {
    cap: usize,
    inner: Mutex<Inner>,
    metrics: Option<Arc<Metrics>>,
}

#[derive(Debug, Default)]
struct Inner {
    next: u64,
    open: BTreeMap<u64, Arc<Activity>>,
}

/// An admitted connection's place in the table; dropping it (when the connection's task
/// ends or is aborted) frees the place.
#[derive(Debug)]
pub(super) struct Entry {
    table: Arc<Table>,
    id: u64,
    /// What the connection is doing.
    pub activity: Arc<Activity>,
}

impl Table {
    /// An empty table admitting `cap` connections at once (at least one); the number of
    /// open connections is reported to `metrics`.
    pub(super) fn new(cap: usize, metrics: Option<Arc<Metrics>>) -> Arc<Table> {
        Arc::new(Table {
            cap: cap.max(1),
            inner: Mutex::new(Inner::default()),
            metrics,
        })
    }

    fn lock(&self) -> MutexGuard<'_, Inner> {
        // The table is consistent after every statement: a panic elsewhere leaves it usable.
        self.inner.lock().unwrap_or_else(PoisonError::into_inner)
    }

    fn report(&self, open: usize) {
        if let Some(m) = &self.metrics {
            m.set_open_connections(open);
        }
    }

    /// Admits a connection accepted now. At the cap, the connection idle the longest (one
    /// that never completed a request head counts as idle since it was accepted) is asked
    /// to stop to make room; if every connection has a request in flight, `None`: the new
    /// one is refused.
    ///
    /// Postcondition: connections not asked to stop number at most the cap. (One asked to
    /// stop keeps its place until its task ends, which for an idle one is at once.)
    pub(super) fn admit(self: &Arc<Self>) -> Option<Entry> {
        let mut inner = self.lock();
        if inner.open.len() >= self.cap {
            let victim = inner
                .open
                .values()
                .filter(|a| a.is_idle() && !a.stop_requested())
                .min_by_key(|a| a.idle_since())?;
            tracing::debug!("at the connection cap: closing the connection idle the longest");
            victim.request_stop();
        }
        let id = inner.next;
        inner.next += 1;
        let activity = Activity::new();
        inner.open.insert(id, activity.clone());
        self.report(inner.open.len());
        Some(Entry {
            table: self.clone(),
            id,
            activity,
        })
    }

    /// Asks every open connection to stop.
    pub(super) fn stop_all(&self) {
        for a in self.lock().open.values() {
            a.request_stop();
        }
    }
}

impl Drop for Entry {
    fn drop(&mut self) {
        let mut inner = self.table.lock();
        inner.open.remove(&self.id);
        self.table.report(inner.open.len());
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn at_the_cap_the_longest_idle_connection_makes_room() {
        let table = Table::new(2, None);
        let first = table.admit().expect("room");
        let second = table.admit().expect("room");
        let third = table.admit().expect("room made");
        assert!(first.activity.stop_requested());
        assert!(!second.activity.stop_requested());
        assert!(!third.activity.stop_requested());
        drop(first);
        assert_eq!(table.lock().open.len(), 2);
    }

    #[test]
    fn at_the_cap_with_every_connection_busy_a_new_one_is_refused() {
        let table = Table::new(2, None);
        let a = table.admit().expect("room");
        let b = table.admit().expect("room");
        let _busy = (a.activity.begin_request(), b.activity.begin_request());
        assert!(table.admit().is_none());
        assert!(!a.activity.stop_requested() && !b.activity.stop_requested());
    }
}
