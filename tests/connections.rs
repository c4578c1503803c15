//! Connection limits of the real binary over real TCP: header and idle timeouts, the
//! connection cap (also under a low open-file limit), a stop bounded by its deadline with
//! clients that never finish, and problem+json answers to requests hyper cannot parse.
//!
//! Time bounds here are liveness bounds with generous slack, not measurements.

#[path = "support/process.rs"]
mod process;

use std::io::{ErrorKind, Read, Write};
use std::net::{SocketAddr, TcpStream};
use std::os::unix::process::CommandExt;
use std::time::{Duration, Instant};

use process::{Server, agent};
use serde_json::Value;

/// An HTTP/1.1 answer read off a raw socket.
#[derive(Debug)]
struct Answer {
    status: u16,
    /// Header names in lower case, with their values.
    headers: Vec<(String, String)>,
    body: Vec<u8>,
}

impl Answer {
    fn header(&self, name: &str) -> Option<&str> {
        self.headers
            .iter()
            .find(|(n, _)| n == name)
            .map(|(_, v)| v.as_str())
    }

    /// Asserts a problem+json answer of `status`.
    fn assert_problem(&self, status: u16) -> Value {
        assert_eq!(self.status, status, "{self:?}");
        assert_eq!(
            self.header("content-type"),
            Some("application/problem+json"),
            "{self:?}"
        );
        let p: Value = serde_json::from_slice(&self.body)
            .unwrap_or_else(|e| panic!("not JSON ({e}): {self:?}"));
        assert_eq!(p["status"], status, "{p}");
        for field in ["type", "title", "detail"] {
            assert!(
                p[field].as_str().is_some_and(|t| !t.is_empty()),
                "{field} in {p}"
            );
        }
        p
    }
}

/// Connects to `base` (`http://ADDR`) with reads bounded by `timeout`.
fn connect(base: &str, timeout: Duration) -> TcpStream {
    let addr: SocketAddr = base
        .strip_prefix("http://")
        .and_then(|a| a.parse().ok())
        .expect("an http://ADDR base");
    let stream = TcpStream::connect_timeout(&addr, Duration::from_secs(10))
        .expect("the server accepts a connection");
    stream
        .set_read_timeout(Some(timeout))
        .expect("a read timeout");
    stream
}

/// Reads one answer's head, and its body when it has a `content-length` (a chunked or
/// unbounded body, such as an event stream's, is left unread).
fn read_answer(stream: &mut TcpStream) -> Answer {
    let mut buf = Vec::new();
    let mut byte = [0u8; 1];
    while !buf.ends_with(b"\r\n\r\n") {
        match stream.read(&mut byte) {
            Ok(1) => buf.push(byte[0]),
            Ok(_) => panic!(
                "the connection closed inside an answer's head: {:?}",
                String::from_utf8_lossy(&buf)
            ),
            Err(e) => panic!("no answer ({e}) after {:?}", String::from_utf8_lossy(&buf)),
        }
    }
    let head = String::from_utf8(buf).expect("a text head");
    let mut lines = head.trim_end().split("\r\n");
    let status = lines
        .next()
        .and_then(|l| l.split(' ').nth(1))
        .and_then(|s| s.parse().ok())
        .unwrap_or_else(|| panic!("a status line in {head:?}"));
    let headers: Vec<(String, String)> = lines
        .filter_map(|l| l.split_once(':'))
        .map(|(n, v)| (n.trim().to_ascii_lowercase(), v.trim().to_owned()))
        .collect();
    let mut answer = Answer {
        status,
        headers,
        body: Vec::new(),
    };
    if let Some(len) = answer.header("content-length") {
        let mut body = vec![0u8; len.parse().expect("a length")];
        stream.read_exact(&mut body).expect("the whole body");
        answer.body = body;
    }
    answer
}

/// Whether the server closed `stream` by `until`: a read gives end-of-file or an error
/// other than a timeout (anything the server sent before closing is passed over).
fn closed_by(stream: &mut TcpStream, until: Instant) -> bool {
    let mut sink = [0u8; 4096];
    loop {
        let left = until.saturating_duration_since(Instant::now());
        stream
            .set_read_timeout(Some(left.max(Duration::from_millis(10))))
            .expect("a read timeout");
        match stream.read(&mut sink) {
            Ok(0) => return true,
            Ok(_) => {}
            Err(e) if matches!(e.kind(), ErrorKind::WouldBlock | ErrorKind::TimedOut) => {
                if Instant::now() >= until {
                    return false;
                }
            }
            Err(_) => return true,
        }
    }
}

/// `GET path` on a kept-alive connection; its answer.
fn get(stream: &mut TcpStream, path: &str) -> Answer {
    write!(stream, "GET {path} HTTP/1.1\r\nHost: winged\r\n\r\n").expect("the request is sent");
    read_answer(stream)
}

/// Opens the change stream on a new connection and reads its head.
fn open_events(base: &str) -> TcpStream {
    let mut stream = connect(base, Duration::from_secs(10));
    let head = get(&mut stream, "/v1/world/events");
    assert_eq!(head.status, 200, "{head:?}");
    assert_eq!(head.header("content-type"), Some("text/event-stream"));
    stream
}

/// Raises this process's open-file limit to its hard limit (the tests hold hundreds of
/// sockets).
fn raise_own_file_limit() {
    let mut limit = libc::rlimit {
        rlim_cur: 0,
        rlim_max: 0,
    };
    // SAFETY: getrlimit and setrlimit only read or write the struct given, alive here.
    unsafe {
        if libc::getrlimit(libc::RLIMIT_NOFILE, &mut limit) == 0 && limit.rlim_cur < limit.rlim_max
        {
            limit.rlim_cur = limit.rlim_max;
            libc::setrlimit(libc::RLIMIT_NOFILE, &limit);
        }
    }
}

#[test]
fn half_open_connections_neither_crowd_out_clients_nor_stay_open() {
    raise_own_file_limit();
    const HALF_OPEN: usize = 500;
    // The server may open only 256 descriptors: its cap is lowered to 256 − 64.
    let server = Server::start_with(
        &[
            "--memory",
            "--demo",
            "--header-timeout",
            "2",
            "--idle-timeout",
            "5",
            "--max-connections",
            "1024",
        ],
        |cmd| {
            // SAFETY: setrlimit is async-signal-safe; the struct lives on this stack.
            unsafe {
                cmd.pre_exec(|| {
                    let limit = libc::rlimit {
                        rlim_cur: 256,
                        rlim_max: 256,
                    };
                    if libc::setrlimit(libc::RLIMIT_NOFILE, &limit) != 0 {
                        return Err(std::io::Error::last_os_error());
                    }
                    Ok(())
                });
            }
        },
    );
    let mut half_open: Vec<TcpStream> = (0..HALF_OPEN)
        .map(|_| {
            let mut s = connect(&server.base, Duration::from_secs(1));
            s.write_all(b"GET /v1/bod").expect("a partial request line");
            s
        })
        .collect();
    let opened = Instant::now();

    // Clients keep being served meanwhile.
    let http = agent(Duration::from_secs(10));
    for round in 0..20 {
        for path in ["/healthz", "/v1/bodies"] {
            let res = http
                .get(format!("{}{path}", server.base))
                .call()
                .unwrap_or_else(|e| panic!("round {round}: {path} failed: {e}"));
            assert_eq!(res.status(), 200, "round {round}: {path}");
        }
    }

    // Every half-open connection is closed within the header timeout plus slack.
    let until = opened + Duration::from_secs(2 + 3);
    let still_open = half_open
        .iter_mut()
        .filter_map(|s| (!closed_by(s, until)).then_some(()))
        .count();
    assert_eq!(still_open, 0, "half-open connections still open");
    // And the server still serves.
    let res = http
        .get(format!("{}/healthz", server.base))
        .call()
        .expect("healthz");
    assert_eq!(res.status(), 200);
    let cap = server
        .log_line("connection cap", Duration::from_secs(10))
        .expect("the connection cap is logged");
    assert!(cap.contains("max_connections=192"), "{cap}");
}

#[test]
fn a_connection_that_sends_nothing_is_closed_after_the_header_timeout() {
    let server = Server::start(&["--memory", "--header-timeout", "1", "--idle-timeout", "30"]);
    let mut silent = connect(&server.base, Duration::from_secs(1));
    let until = Instant::now() + Duration::from_secs(1 + 5);
    assert!(
        closed_by(&mut silent, until),
        "the silent connection is open"
    );
}

#[test]
fn idle_keep_alive_connections_close_but_an_open_event_stream_does_not() {
    const IDLE: u64 = 5;
    let server = Server::start(&[
        "--memory",
        "--demo",
        "--header-timeout",
        "2",
        "--idle-timeout",
        &IDLE.to_string(),
    ]);
    let mut events = open_events(&server.base);

    let mut kept = connect(&server.base, Duration::from_secs(10));
    let res = get(&mut kept, "/healthz");
    assert_eq!(res.status, 200);
    let idle_from = Instant::now();
    assert!(
        closed_by(&mut kept, idle_from + Duration::from_secs(IDLE + 5)),
        "the idle connection is open"
    );
    // Closed by the idle timeout, not before it (the header timeout is shorter).
    assert!(
        idle_from.elapsed() >= Duration::from_secs(IDLE - 1),
        "closed after {:?}",
        idle_from.elapsed()
    );

    // The event stream, open all along, still delivers.
    let http = agent(Duration::from_secs(10));
    let made = http
        .post(format!("{}/v1/bodies", server.base))
        .send_json(serde_json::json!({"shape": {"type": "box", "size": [1, 1, 1]}}))
        .expect("a write");
    assert_eq!(made.status(), 201);
    events
        .set_read_timeout(Some(Duration::from_secs(10)))
        .expect("a read timeout");
    let mut seen = Vec::new();
    let mut chunk = [0u8; 4096];
    while !String::from_utf8_lossy(&seen).contains("event: change") {
        match events.read(&mut chunk) {
            Ok(0) => panic!(
                "the event stream was closed: {}",
                String::from_utf8_lossy(&seen)
            ),
            Ok(n) => seen.extend_from_slice(&chunk[..n]),
            Err(e) => panic!("no change event ({e}): {}", String::from_utf8_lossy(&seen)),
        }
    }
}

#[test]
fn a_stop_ends_within_its_deadline_despite_half_open_connections() {
    let mut server = Server::start(&["--memory", "--demo", "--shutdown-deadline", "3"]);
    let _half_open: Vec<TcpStream> = (0..100)
        .map(|_| {
            let mut s = connect(&server.base, Duration::from_secs(1));
            s.write_all(b"GET /v1/bod").expect("a partial request line");
            s
        })
        .collect();
    let mut events = open_events(&server.base);
    let status = server
        .terminate_within(Duration::from_secs(3 + 7))
        .expect("the server exits within its shutdown deadline and slack");
    assert!(status.success(), "{status:?}");
    assert!(
        closed_by(&mut events, Instant::now() + Duration::from_secs(2)),
        "the event stream is open after the exit"
    );
}

#[test]
fn requests_hyper_cannot_parse_are_answered_with_problems() {
    let server = Server::start(&["--memory"]);
    let big = "a".repeat(100 * 1024);
    let cases: Vec<(&str, Vec<u8>, &[u16])> = vec![
        ("a malformed request", b"GARBAGE\r\n\r\n".to_vec(), &[400]),
        (
            "a 100 KiB header",
            format!("GET /healthz HTTP/1.1\r\nHost: winged\r\nX-Big: {big}\r\n\r\n").into_bytes(),
            &[431],
        ),
        (
            "a 100 KiB URI",
            format!("GET /{big} HTTP/1.1\r\nHost: winged\r\n\r\n").into_bytes(),
            &[414, 431],
        ),
    ];
    for (what, request, statuses) in cases {
        let mut s = connect(&server.base, Duration::from_secs(10));
        s.write_all(&request).expect("the request is sent");
        let answer = read_answer(&mut s);
        assert!(
            statuses.contains(&answer.status),
            "{what}: answered {}",
            answer.status
        );
        answer.assert_problem(answer.status);
        assert!(
            closed_by(&mut s, Instant::now() + Duration::from_secs(5)),
            "{what}: the connection is open after the error"
        );
    }
    let mut s = connect(&server.base, Duration::from_secs(10));
    assert_eq!(get(&mut s, "/healthz").status, 200);
}

#[test]
fn past_the_cap_busy_connections_refuse_newcomers_and_idle_ones_make_room() {
    // Eight event streams fill the cap with requests in flight: a ninth is refused.
    let server = Server::start(&["--memory", "--max-connections", "8"]);
    let _streams: Vec<TcpStream> = (0..8).map(|_| open_events(&server.base)).collect();
    let mut ninth = connect(&server.base, Duration::from_secs(10));
    let refused = get(&mut ninth, "/healthz");
    refused.assert_problem(503);
    assert!(refused.header("retry-after").is_some(), "{refused:?}");
    assert_eq!(refused.header("connection"), Some("close"));
    assert!(closed_by(
        &mut ninth,
        Instant::now() + Duration::from_secs(5)
    ));

    // Eight idle kept-alive connections: a ninth is served and the oldest is closed.
    let server = Server::start(&["--memory", "--max-connections", "8"]);
    let mut idle: Vec<TcpStream> = (0..8)
        .map(|_| {
            let mut s = connect(&server.base, Duration::from_secs(10));
            assert_eq!(get(&mut s, "/healthz").status, 200);
            s
        })
        .collect();
    let mut ninth = connect(&server.base, Duration::from_secs(10));
    assert_eq!(get(&mut ninth, "/healthz").status, 200);
    assert!(
        closed_by(&mut idle[0], Instant::now() + Duration::from_secs(5)),
        "the oldest idle connection is open"
    );
    // The others are still served.
    assert_eq!(get(&mut idle[1], "/healthz").status, 200);
}
