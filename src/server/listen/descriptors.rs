//! How many connections fit in the file descriptors the process may open.

/// Descriptors kept out of the connection cap for everything else the server opens: the
/// listening socket, the journal (database, write-ahead log, shared memory), snapshot files
/// being written or read, the runtime's own, standard streams.
pub const RESERVED_DESCRIPTORS: u64 = 64;

/// The connection cap in force.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) struct Cap {
    /// Connections served at once.
    pub connections: usize,
    /// The open-file limit (`RLIMIT_NOFILE`, soft) when it lowered the cap below the one
    /// asked for.
    pub lowered_by: Option<u64>,
}

/// The soft `RLIMIT_NOFILE` of this process; `None` if unlimited or unknown.
pub(super) fn open_file_limit() -> Option<u64> {
    let mut limit = libc::rlimit {
        rlim_cur: 0,
        rlim_max: 0,
    };
    // SAFETY: getrlimit only writes the struct it is given, which lives for the call.
    let read = unsafe { libc::getrlimit(libc::RLIMIT_NOFILE, &mut limit) };
    if read != 0 || limit.rlim_cur == libc::RLIM_INFINITY {
        return None;
    }
    Some(limit.rlim_cur)
}

/// The cap for `requested` connections under the open-file limit `nofile`: at most
/// `nofile − RESERVED_DESCRIPTORS` (and at least one connection, however low the limit).
///
/// Precondition: `requested ≥ 1`. Postcondition: `1 ≤ connections ≤ requested`.
pub(super) fn connection_cap(requested: usize, nofile: Option<u64>) -> Cap {
    let requested = requested.max(1);
    let fits = nofile.map(|n| {
        usize::try_from(n.saturating_sub(RESERVED_DESCRIPTORS))
            .unwrap_or(usize::MAX)
            .max(1)
    });
    match fits {
        Some(fits) if fits < requested => Cap {
            connections: fits,
            lowered_by: nofile,
        },
        _ => Cap {
            connections: requested,
            lowered_by: None,
        },
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_cap_leaves_the_reserve_free() {
        assert_eq!(
            connection_cap(1024, Some(256)),
            Cap {
                connections: 192,
                lowered_by: Some(256)
            }
        );
        assert_eq!(
            connection_cap(100, Some(256)),
            Cap {
                connections: 100,
                lowered_by: None
            }
        );
        assert_eq!(connection_cap(1024, None).connections, 1024);
        assert_eq!(connection_cap(1024, Some(10)).connections, 1);
    }

    #[test]
    fn this_process_has_a_limit_or_none() {
        if let Some(n) = open_file_limit() {
            assert!(n > 0);
        }
    }
}
