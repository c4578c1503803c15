//! Following the world over real HTTP: preconditions on writes, the changes after a
//! revision, and the Server-Sent Events stream with `Last-Event-ID` resumption.

#[path = "support/http.rs"]
mod support;

use std::io::{BufRead, BufReader, Read};
use std::sync::{Arc, Barrier};
use std::thread;
use std::time::Duration;

use serde_json::{Value, json};
use support::TestServer;
use winged::model::World;
use winged::server::Limits;

fn create_box(s: &TestServer, name: &str) -> (u64, u64) {
    let made = s
        .post(
            "/v1/bodies",
            &json!({"name": name, "shape": {"type": "box", "size": [1, 1, 1]}}),
        )
        .ok();
    (
        made["id"].as_u64().expect("an id"),
        made["revision"].as_u64().expect("a revision"),
    )
}

fn revision(s: &TestServer) -> u64 {
    s.get("/v1/world").ok()["revision"]
        .as_u64()
        .expect("a revision")
}

#[test]
fn a_stale_precondition_is_refused_with_412_and_changes_nothing() {
    let s = TestServer::start();
    let (id, r) = create_box(&s, "crate");
    let agent = s.agent();
    let patch = |if_match: Option<&str>, body: Value| {
        let mut req = agent.patch(&s.url(&format!("/v1/bodies/{id}")));
        if let Some(m) = if_match {
            req = req.header("If-Match", m);
        }
        support::Reply::from(req.send_json(&body))
    };
    // The ETag of a read is the revision a write can be conditioned on.
    let read = agent
        .get(&s.url(&format!("/v1/bodies/{id}")))
        .call()
        .expect("a read");
    assert_eq!(
        read.headers().get("etag").and_then(|v| v.to_str().ok()),
        Some(format!("\"{r}\"").as_str())
    );

    let ok = patch(Some(&format!("\"{r}\"")), json!({"name": "crate-1"})).ok();
    assert_eq!(ok["revision"], r + 1);

    // The same precondition again: the world has moved on.
    let stale = patch(Some(&format!("\"{r}\"")), json!({"name": "crate-2"}));
    let p = stale.problem(412);
    assert_eq!(p["revision"], r + 1, "{p}");
    assert_eq!(p["type"], "urn:winged:problem:revision-moved");
    // In the body instead of the header.
    let stale = patch(None, json!({"name": "crate-2", "expected_revision": r}));
    stale.problem(412);
    assert_eq!(revision(&s), r + 1, "a refused write changes nothing");
    assert_eq!(s.get(&format!("/v1/bodies/{id}")).ok()["name"], "crate-1");

    // The current revision, in the body, passes.
    let ok = patch(None, json!({"name": "crate-2", "expected_revision": r + 1})).ok();
    assert_eq!(ok["revision"], r + 2);
    // A weak tag and a bare number are understood; `*` is no precondition.
    patch(Some(&format!("W/\"{}\"", r + 2)), json!({"name": "c3"})).ok();
    patch(Some(&format!("{}", r + 3)), json!({"name": "c4"})).ok();
    patch(Some("*"), json!({"name": "c5"})).ok();

    // Malformed or contradictory preconditions are the client's error.
    patch(Some("\"soon\""), json!({"name": "x"})).problem(400);
    patch(Some("\"1\", \"2\""), json!({"name": "x"})).problem(400);
    let now = revision(&s);
    patch(
        Some(&format!("\"{now}\"")),
        json!({"name": "x", "expected_revision": now + 5}),
    )
    .problem(400);
    patch(None, json!({"name": "x", "expected_revision": "latest"})).problem(400);
    assert_eq!(revision(&s), now);

    // Writes without a body take the header: a stale DELETE keeps the body.
    let del = support::Reply::from(
        agent
            .delete(&s.url(&format!("/v1/bodies/{id}")))
            .header("If-Match", format!("\"{}\"", now - 1))
            .call(),
    );
    del.problem(412);
    s.get(&format!("/v1/bodies/{id}")).ok();
}

#[test]
fn changes_since_a_revision_name_what_changed_and_ask_for_resync_when_too_old() {
    let limits = Limits {
        history: 8,
        ..Limits::default()
    };
    let s = TestServer::with_limits(World::new(), limits);
    let r0 = revision(&s);
    let (table, _) = create_box(&s, "table");
    let (cup, _) = create_box(&s, "cup");
    s.patch(&format!("/v1/bodies/{cup}"), &json!({"parent": table}))
        .ok();
    s.put(
        "/v1/cameras/eye",
        &json!({"look_at": {"eye": [5, 0, 2], "target": [0, 0, 0], "up": [0, 0, 1]},
                "intrinsics": {"width": 64, "height": 48, "fx": 50, "fy": 50, "cx": 32, "cy": 24}}),
    )
    .ok();
    s.delete(&format!("/v1/bodies/{table}")).ok();

    let all = s.get(&format!("/v1/world/changes?since={r0}")).ok();
    assert_eq!(all["resync"], false);
    let changes = all["changes"].as_array().expect("changes");
    let revs: Vec<u64> = changes
        .iter()
        .map(|c| c["revision"].as_u64().unwrap())
        .collect();
    assert_eq!(revs, (r0 + 1..=r0 + 5).collect::<Vec<_>>());
    let kinds: Vec<&str> = changes
        .iter()
        .map(|c| c["edit"].as_str().unwrap())
        .collect();
    assert_eq!(
        kinds,
        [
            "create_body",
            "create_body",
            "patch_body",
            "put_camera",
            "delete_body"
        ]
    );
    // The re-parenting names the body's changed fields and both suparts' parts.
    let reparent = &changes[2]["changes"];
    assert_eq!(
        reparent[0],
        json!({"action": "updated", "kind": "body", "id": cup, "fields": ["parent", "pose"]})
    );
    assert!(
        reparent.as_array().unwrap().contains(
            &json!({"action": "updated", "kind": "body", "id": table, "fields": ["parts"]})
        ),
        "{reparent}"
    );
    assert_eq!(
        changes[3]["changes"][0],
        json!({"action": "added", "kind": "camera", "name": "eye"})
    );
    // Deleting the table kills the cup with it.
    let removed: Vec<u64> = changes[4]["changes"]
        .as_array()
        .unwrap()
        .iter()
        .filter(|c| c["action"] == "removed")
        .map(|c| c["id"].as_u64().unwrap())
        .collect();
    assert_eq!(removed.len(), 2);
    assert!(removed.contains(&table) && removed.contains(&cup));

    // Paging.
    let page = s.get(&format!("/v1/world/changes?since={r0}&limit=2")).ok();
    assert_eq!(page["changes"].as_array().unwrap().len(), 2);
    assert_eq!(page["more"], true);
    // Up to date: nothing.
    let now = revision(&s);
    let none = s.get(&format!("/v1/world/changes?since={now}")).ok();
    assert_eq!(none["changes"], json!([]));
    assert_eq!(none["resync"], false);

    // Push the oldest changes out of the 8 kept.
    for i in 0..10 {
        s.put(
            "/v1/lights/sun",
            &json!({"type": "sun", "direction": [0, 0, -1], "intensity": 0.5 + i as f64 / 100.0}),
        )
        .ok();
    }
    let old = s.get(&format!("/v1/world/changes?since={r0}")).ok();
    assert_eq!(old["resync"], true);
    assert_eq!(old["revision"], revision(&s));
    // A revision from the future (say, of a world restored from an older backup) too.
    let ahead = s
        .get(&format!("/v1/world/changes?since={}", revision(&s) + 100))
        .ok();
    assert_eq!(ahead["resync"], true);

    s.get("/v1/world/changes").problem(400);
    s.get("/v1/world/changes?since=-1").problem(400);
    s.get("/v1/world/changes?since=0&colour=red").problem(400);
}

/// One Server-Sent Event.
#[derive(Debug, Default)]
struct Event {
    id: Option<u64>,
    kind: String,
    data: String,
}

/// Reads events from an SSE body.
struct Events {
    lines: BufReader<Box<dyn Read + Send>>,
}

impl Events {
    fn open(s: &TestServer, last_event_id: Option<u64>, since: Option<u64>) -> Events {
        let agent: ureq::Agent = ureq::Agent::config_builder()
            .timeout_global(Some(Duration::from_secs(60)))
            .build()
            .into();
        let url = match since {
            Some(n) => s.url(&format!("/v1/world/events?since={n}")),
            None => s.url("/v1/world/events"),
        };
        let mut req = agent.get(&url).header("Accept", "text/event-stream");
        if let Some(id) = last_event_id {
            req = req.header("Last-Event-ID", id.to_string());
        }
        let res = req.call().expect("the stream opens");
        assert_eq!(
            res.headers()
                .get("content-type")
                .and_then(|v| v.to_str().ok()),
            Some("text/event-stream")
        );
        let reader: Box<dyn Read + Send> = Box::new(res.into_body().into_reader());
        Events {
            lines: BufReader::new(reader),
        }
    }

    /// The next event (comments and keep-alives skipped).
    fn next(&mut self) -> Event {
        let mut e = Event::default();
        loop {
            let mut line = String::new();
            let n = self.lines.read_line(&mut line).expect("the stream reads");
            assert!(n > 0, "the stream ended early");
            let line = line.trim_end_matches(['\r', '\n']);
            if line.is_empty() {
                if !e.kind.is_empty() || !e.data.is_empty() {
                    return e;
                }
                continue;
            }
            if line.starts_with(':') {
                continue;
            }
            let (field, value) = line.split_once(':').unwrap_or((line, ""));
            let value = value.strip_prefix(' ').unwrap_or(value);
            match field {
                "id" => e.id = value.parse().ok(),
                "event" => e.kind = value.to_string(),
                "data" => e.data.push_str(value),
                _ => {}
            }
        }
    }

    /// The next `change` event's revision, checking that its data agrees.
    fn next_change(&mut self) -> u64 {
        let e = self.next();
        assert_eq!(e.kind, "change", "{e:?}");
        let data: Value = serde_json::from_str(&e.data).expect("JSON data");
        let id = e.id.expect("an id");
        assert_eq!(data["revision"], id);
        assert_eq!(data["edit"], "patch_body");
        id
    }
}

#[test]
fn three_subscribers_see_every_change_once_and_in_order_while_eight_clients_write() {
    const WRITERS: usize = 8;
    const EACH: usize = 25;
    const TOTAL: u64 = (WRITERS * EACH) as u64;
    let s = Arc::new(TestServer::start());
    let bodies: Vec<u64> = (0..WRITERS)
        .map(|i| create_box(&s, &format!("block-{i}")).0)
        .collect();
    let r0 = revision(&s);

    // Subscribers connect (from r0) before any writer starts.
    let ready = Arc::new(Barrier::new(3 + WRITERS));
    let mut subscribers = Vec::new();
    for k in 0..3 {
        let (s, ready) = (s.clone(), ready.clone());
        subscribers.push(thread::spawn(move || {
            let mut seen = Vec::new();
            let mut events = Events::open(&s, None, Some(r0));
            ready.wait();
            if k == 2 {
                // This one drops its connection part-way and resumes from its last id.
                for _ in 0..60 {
                    seen.push(events.next_change());
                }
                drop(events);
                thread::sleep(Duration::from_millis(50));
                events = Events::open(&s, seen.last().copied(), None);
            }
            while (seen.len() as u64) < TOTAL {
                seen.push(events.next_change());
            }
            seen
        }));
    }
    let mut writers = Vec::new();
    for (i, &body) in bodies.iter().enumerate() {
        let (s, ready) = (s.clone(), ready.clone());
        writers.push(thread::spawn(move || {
            ready.wait();
            for j in 0..EACH {
                // Each pose differs from the one before, so each patch is a change.
                let x = (i * 100 + j + 1) as f64;
                s.patch(
                    &format!("/v1/bodies/{body}"),
                    &json!({"pose": {"position": [x, 0, 0], "rotation": [0, 0, 0, 1]}}),
                )
                .ok();
            }
        }));
    }
    for w in writers {
        w.join().expect("a writer");
    }
    let want: Vec<u64> = (r0 + 1..=r0 + TOTAL).collect();
    for (k, sub) in subscribers.into_iter().enumerate() {
        let seen = sub.join().expect("a subscriber");
        assert_eq!(seen, want, "subscriber {k}");
    }
    assert_eq!(revision(&s), r0 + TOTAL);

    // A subscriber whose last id is older than the history kept is told to resync.
    let small = TestServer::with_limits(
        World::new(),
        Limits {
            history: 2,
            ..Limits::default()
        },
    );
    for i in 0..5 {
        create_box(&small, &format!("b{i}"));
    }
    let mut events = Events::open(&small, Some(0), None);
    let e = events.next();
    assert_eq!(e.kind, "resync");
    let data: Value = serde_json::from_str(&e.data).expect("JSON");
    assert_eq!(data["revision"], revision(&small));
}
