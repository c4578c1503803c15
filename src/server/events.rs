//! The change feed: recent [`Change`]s kept in memory for `GET /v1/world/changes`, and
//! pushed live to `GET /v1/world/events` subscribers as Server-Sent Events.
//!
//! The world's owner publishes each batch of changes after it is durable, in revision
//! order, so a client never hears of a write that a crash could take back. The feed
//! keeps the newest `capacity` changes; a client whose last seen revision is older than
//! that must resync from a full read of the world.
//!
//! A subscriber first subscribes to the live channel, then reads the backlog from the
//! history, and skips live changes it has already sent: it sees every change exactly
//! once and in order. A subscriber that falls behind the live channel catches up from
//! the history, or is told to resync when the history no longer reaches back.

use std::collections::VecDeque;
use std::convert::Infallible;
use std::sync::{Arc, RwLock};

use axum::response::sse::Event;
use futures_util::Stream;
use tokio::sync::{broadcast, watch};

use super::changes::Change;

/// How many changes the live channel buffers per subscriber before it falls back to the
/// history.
const LIVE_BUFFER: usize = 1024;

/// Recent changes and the live channel. Shared as `Arc<Feed>`.
pub struct Feed {
    history: RwLock<History>,
    live: broadcast::Sender<Arc<Change>>,
    closing: watch::Sender<bool>,
}

struct History {
    changes: VecDeque<Arc<Change>>,
    capacity: usize,
    /// The revision of the newest durable write.
    revision: u64,
}

/// The answer to "what changed after revision N".
#[derive(Debug, Clone)]
pub enum Since {
    /// The changes after N, oldest first (at most the limit asked for).
    Changes {
        /// The changes.
        changes: Vec<Arc<Change>>,
        /// Whether more changes follow the last one given.
        more: bool,
        /// The world's revision.
        revision: u64,
    },
    /// N is older than the history kept (or newer than the world): read the world
    /// whole again.
    Resync {
        /// The world's revision.
        revision: u64,
        /// The oldest revision whose change is still kept, if any.
        oldest: Option<u64>,
    },
}

impl Feed {
    /// A feed at `revision` keeping up to `capacity` changes (at least one), seeded with
    /// `recent` (oldest first; only the newest `capacity` are kept).
    pub fn new(capacity: usize, revision: u64, recent: Vec<Change>) -> Arc<Feed> {
        let capacity = capacity.max(1);
        let skip = recent.len().saturating_sub(capacity);
        let changes = recent.into_iter().skip(skip).map(Arc::new).collect();
        let (live, _) = broadcast::channel(LIVE_BUFFER);
        let (closing, _) = watch::channel(false);
        Arc::new(Feed {
            history: RwLock::new(History {
                changes,
                capacity,
                revision,
            }),
            live,
            closing,
        })
    }

    /// Publishes durable changes, in revision order, each newer than the last published.
    pub fn publish(&self, changes: Vec<Change>) {
        let changes: Vec<Arc<Change>> = changes.into_iter().map(Arc::new).collect();
        {
            let mut h = self.history.write().unwrap_or_else(|p| p.into_inner());
            for c in &changes {
                if h.changes.len() == h.capacity {
                    h.changes.pop_front();
                }
                h.revision = c.revision;
                h.changes.push_back(c.clone());
            }
        }
        for c in changes {
            // No subscriber is not an error.
            let _ = self.live.send(c);
        }
    }

    /// Sets the revision after the world was reloaded from storage (changes that were
    /// never durable are forgotten; none of them was published).
    pub fn reset_revision(&self, revision: u64) {
        let mut h = self.history.write().unwrap_or_else(|p| p.into_inner());
        h.revision = revision;
        while h.changes.back().is_some_and(|c| c.revision > revision) {
            h.changes.pop_back();
        }
    }

    /// The revision of the newest published change (or the start revision).
    pub fn revision(&self) -> u64 {
        self.history
            .read()
            .unwrap_or_else(|p| p.into_inner())
            .revision
    }

    /// The changes after revision `n`, at most `limit` of them.
    pub fn since(&self, n: u64, limit: usize) -> Since {
        let h = self.history.read().unwrap_or_else(|p| p.into_inner());
        let oldest = h.changes.front().map(|c| c.revision);
        if n == h.revision {
            return Since::Changes {
                changes: Vec::new(),
                more: false,
                revision: h.revision,
            };
        }
        // Change n+1 must still be kept (revisions in the history are consecutive).
        match oldest {
            Some(o) if n < h.revision && o <= n + 1 => {
                let start = usize::try_from(n + 1 - o).unwrap_or(usize::MAX);
                let changes: Vec<Arc<Change>> =
                    h.changes.iter().skip(start).take(limit).cloned().collect();
                let more = start.saturating_add(changes.len()) < h.changes.len();
                Since::Changes {
                    changes,
                    more,
                    revision: h.revision,
                }
            }
            _ => Since::Resync {
                revision: h.revision,
                oldest,
            },
        }
    }

    /// Ends every event stream (the server is shutting down).
    pub fn close(&self) {
        self.closing.send_replace(true);
    }

    /// An SSE stream of every change after revision `last` (the `Last-Event-ID`), then
    /// live ones until the feed closes. Each event has `id` = its revision, type
    /// `change` and the [`Change`] as JSON data. When `last` is too old for the history,
    /// the stream sends one `resync` event and ends.
    pub fn stream(
        self: &Arc<Self>,
        last: u64,
    ) -> impl Stream<Item = Result<Event, Infallible>> + use<> {
        let state = Subscriber {
            live: self.live.subscribe(),
            feed: self.clone(),
            closing: self.closing.subscribe(),
            pending: VecDeque::new(),
            last,
            backlog_read: false,
            done: false,
        };
        futures_util::stream::unfold(state, |mut s| async move {
            let event = s.next().await?;
            Some((Ok(event), s))
        })
    }
}

struct Subscriber {
    live: broadcast::Receiver<Arc<Change>>,
    feed: Arc<Feed>,
    closing: watch::Receiver<bool>,
    pending: VecDeque<Arc<Change>>,
    last: u64,
    backlog_read: bool,
    done: bool,
}

enum Step {
    Send(Arc<Change>),
    CatchUp,
    End,
}

impl Subscriber {
    /// The next event, or `None` when the stream ends.
    async fn next(&mut self) -> Option<Event> {
        if self.done {
            return None;
        }
        if !self.backlog_read {
            self.backlog_read = true;
            if let Some(resync) = self.catch_up() {
                return Some(resync);
            }
        }
        loop {
            while let Some(c) = self.pending.pop_front() {
                if c.revision > self.last {
                    self.last = c.revision;
                    return Some(change_event(&c));
                }
            }
            if *self.closing.borrow() {
                return None;
            }
            let step = tokio::select! {
                r = self.live.recv() => match r {
                    Ok(c) if c.revision <= self.last => continue,
                    Ok(c) if c.revision == self.last + 1 => Step::Send(c),
                    Ok(_) | Err(broadcast::error::RecvError::Lagged(_)) => Step::CatchUp,
                    Err(broadcast::error::RecvError::Closed) => Step::End,
                },
                _ = self.closing.changed() => Step::End,
            };
            match step {
                Step::Send(c) => {
                    self.last = c.revision;
                    return Some(change_event(&c));
                }
                Step::CatchUp => {
                    if let Some(resync) = self.catch_up() {
                        return Some(resync);
                    }
                }
                Step::End => {
                    self.done = true;
                    return None;
                }
            }
        }
    }

    /// Queues every kept change after `last`; a `resync` event (and the end of the
    /// stream) when the history no longer reaches back that far.
    fn catch_up(&mut self) -> Option<Event> {
        match self.feed.since(self.last, usize::MAX) {
            Since::Changes { changes, .. } => {
                self.pending.extend(changes);
                None
            }
            Since::Resync { revision, oldest } => {
                self.done = true;
                let data = Resync {
                    resync: true,
                    since: self.last,
                    revision,
                    oldest,
                };
                let text = serde_json::to_string(&data).unwrap_or_else(|_| "{}".into());
                Some(Event::default().event("resync").data(text))
            }
        }
    }
}

/// The data of a `resync` event: the history no longer reaches back to `since`.
#[derive(serde::Serialize)]
struct Resync {
    /// Always `true`.
    resync: bool,
    /// The revision the stream was to follow on from.
    since: u64,
    /// The world's revision.
    revision: u64,
    /// The oldest revision whose change is still kept, if any.
    oldest: Option<u64>,
}

fn change_event(c: &Change) -> Event {
    let data = serde_json::to_string(c).unwrap_or_else(|_| "{}".into());
    Event::default()
        .id(c.revision.to_string())
        .event("change")
        .data(data)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn change(revision: u64) -> Change {
        Change {
            revision,
            edit: "put_camera".into(),
            changes: Vec::new(),
        }
    }

    fn revisions(s: &Since) -> Vec<u64> {
        match s {
            Since::Changes { changes, .. } => changes.iter().map(|c| c.revision).collect(),
            Since::Resync { .. } => panic!("unexpected resync"),
        }
    }

    #[test]
    fn since_serves_what_is_kept_and_asks_for_resync_otherwise() {
        let feed = Feed::new(3, 10, Vec::new());
        assert_eq!(revisions(&feed.since(10, 100)), Vec::<u64>::new());
        assert!(matches!(feed.since(9, 100), Since::Resync { .. }));
        feed.publish((11..=14).map(change).collect());
        // Only 12, 13, 14 are kept.
        assert_eq!(revisions(&feed.since(11, 100)), vec![12, 13, 14]);
        assert_eq!(revisions(&feed.since(13, 100)), vec![14]);
        assert!(matches!(
            feed.since(10, 100),
            Since::Resync {
                oldest: Some(12),
                ..
            }
        ));
        // Ahead of the world: resync too.
        assert!(matches!(feed.since(15, 100), Since::Resync { .. }));
        match feed.since(11, 2) {
            Since::Changes { changes, more, .. } => {
                assert_eq!(changes.len(), 2);
                assert!(more);
            }
            Since::Resync { .. } => panic!("unexpected resync"),
        }
    }

    #[test]
    fn reset_drops_changes_past_the_durable_revision() {
        let feed = Feed::new(10, 0, (1..=3).map(change).collect());
        feed.reset_revision(2);
        assert_eq!(feed.revision(), 2);
        assert_eq!(revisions(&feed.since(0, 100)), vec![1, 2]);
    }
}
