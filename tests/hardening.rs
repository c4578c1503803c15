//! What a hostile or careless client, a SIGKILL or a damaged data directory can do to
//! the real binary: every write is checked against the world's range when it is
//! planned, so a world the server accepted always reloads; no answer carries `null`
//! for a number; a write that changes nothing is no revision; names are refused when
//! they could not be read back as written; a journal that lost acknowledged writes is
//! refused at start (or, with `--accept-loss`, resumed past them) and never reissues an
//! acknowledged id.

#[path = "support/process.rs"]
mod process;

use std::path::{Path, PathBuf};
use std::time::Duration;

use process::{Server, agent, check_data};
use serde_json::{Value, json};

/// One answer: status and JSON body (`Null` when the body is not JSON).
fn call(a: &ureq::Agent, method: &str, url: &str, body: Option<&Value>) -> (u16, Value) {
    let res = match (method, body) {
        ("GET", _) => a.get(url).call(),
        ("POST", Some(b)) => a.post(url).send_json(b),
        ("POST", None) => a.post(url).send_empty(),
        ("PATCH", Some(b)) => a.patch(url).send_json(b),
        _ => unreachable!("{method}"),
    };
    let mut res = res.unwrap_or_else(|e| panic!("{method} {url}: {e}"));
    let status = res.status().as_u16();
    let problem = res
        .headers()
        .get("content-type")
        .is_some_and(|t| t == "application/problem+json");
    let v = res.body_mut().read_json::<Value>().unwrap_or(Value::Null);
    if status >= 400 {
        assert!(problem, "{method} {url}: {status} is not problem+json: {v}");
    }
    (status, v)
}

/// The paths in `v` that hold `null`.
fn nulls(v: &Value, at: &str, out: &mut Vec<String>) {
    match v {
        Value::Null => out.push(at.to_owned()),
        Value::Array(a) => a
            .iter()
            .enumerate()
            .for_each(|(i, x)| nulls(x, &format!("{at}/{i}"), out)),
        Value::Object(o) => o
            .iter()
            .for_each(|(k, x)| nulls(x, &format!("{at}/{k}"), out)),
        _ => {}
    }
}

fn assert_no_null(v: &Value, what: &str) {
    let mut out = Vec::new();
    nulls(v, "", &mut out);
    assert!(out.is_empty(), "{what}: null at {out:?}");
}

fn body_id(a: &ureq::Agent, base: &str, name: &str) -> u64 {
    let (s, v) = call(a, "GET", &format!("{base}/v1/bodies?name={name}"), None);
    assert_eq!(s, 200, "{v}");
    v["bodies"][0]["id"].as_u64().expect("the body exists")
}

fn revision(a: &ureq::Agent, base: &str) -> u64 {
    let (_, w) = call(a, "GET", &format!("{base}/v1/world"), None);
    w["revision"].as_u64().expect("a revision")
}

fn data_arg(dir: &Path) -> String {
    dir.display().to_string()
}

#[test]
fn a_reflection_about_a_far_point_is_refused_and_the_directory_always_reloads() {
    let dir = tempfile::tempdir().unwrap();
    let data = data_arg(dir.path());
    let s = Server::start(&["--data", &data, "--demo"]);
    let a = agent(Duration::from_secs(30));
    let base = s.base.clone();
    let table = body_id(&a, &base, "table");
    let before = revision(&a, &base);
    let (_, list_before) = call(&a, "GET", &format!("{base}/v1/bodies"), None);

    // The write that once produced a locus of -1.6e308 and, after DUAL, an infinite one.
    let far = json!({"op": "reflect", "normal": [0, 1, 0], "point": [0, -8e307, 0]});
    let (st, p) = call(
        &a,
        "POST",
        &format!("{base}/v1/bodies/{table}/transform"),
        Some(&far),
    );
    assert_eq!(st, 422, "{p}");
    assert!(p["type"].as_str().unwrap().ends_with("out-of-range"), "{p}");
    assert_eq!(
        revision(&a, &base),
        before,
        "a refused write is no revision"
    );
    let (_, list_after) = call(&a, "GET", &format!("{base}/v1/bodies"), None);
    assert_eq!(list_after, list_before, "a refused write changed the world");

    // A reflection within range, DUAL, snapshots between writes: all reload.
    let near = json!({"op": "reflect", "normal": [0, 1, 0], "point": [0, -3, 0]});
    let url = format!("{base}/v1/bodies/{table}/transform");
    assert_eq!(call(&a, "POST", &url, Some(&near)).0, 200);
    let dual = format!("{base}/v1/bodies/{table}/dual");
    let (st, d) = call(&a, "POST", &dual, None);
    assert_eq!(st, 200, "{d}");
    let snapshot = format!("{base}/v1/admin/snapshot");
    assert_eq!(call(&a, "POST", &snapshot, None).0, 200);
    let cube = json!({"name": "late", "shape": {"type": "box", "size": [1, 1, 1]}});
    assert_eq!(
        call(&a, "POST", &format!("{base}/v1/bodies"), Some(&cube)).0,
        201
    );
    assert_eq!(call(&a, "POST", &snapshot, None).0, 200);
    let (_, topology) = call(
        &a,
        "GET",
        &format!("{base}/v1/bodies/{table}/topology"),
        None,
    );
    assert_no_null(&topology, "the dual's topology");
    let (_, world) = call(&a, "GET", &format!("{base}/v1/bodies"), None);
    assert!(s.stop().success());

    check_data(dir.path());
    let s = Server::start(&["--data", &data]);
    let (_, reloaded) = call(&a, "GET", &format!("{}/v1/bodies", s.base), None);
    assert_eq!(reloaded, world, "the reloaded world differs");
}

#[test]
fn huge_numbers_are_refused_or_answered_with_numbers() {
    let s = Server::start(&["--memory", "--demo"]);
    let a = agent(Duration::from_secs(30));
    let base = s.base.clone();
    let table = body_id(&a, &base, "table");
    let before = revision(&a, &base);

    let huge = json!({"name": "huge", "shape": {"type": "box", "size": [1e308, 1e308, 1e308]}});
    let (st, p) = call(&a, "POST", &format!("{base}/v1/bodies"), Some(&huge));
    assert_eq!(st, 422, "{p}");
    for factor in [1e300, 1e-12] {
        let dilate = json!({"op": "dilate", "factor": factor});
        let url = format!("{base}/v1/bodies/{table}/transform");
        let (st, p) = call(&a, "POST", &url, Some(&dilate));
        assert_eq!(st, 422, "dilate by {factor}: {p}");
    }
    assert_eq!(revision(&a, &base), before);

    let (_, list) = call(&a, "GET", &format!("{base}/v1/bodies"), None);
    assert_no_null(&list, "GET /v1/bodies");

    // A centre beyond the query limit is a mistake in the query, not `distance: null`.
    let (st, p) = call(
        &a,
        "GET",
        &format!("{base}/v1/spatial/nearest?x=0&y=0&z=1e155"),
        None,
    );
    assert_eq!(st, 422, "{p}");
    assert!(
        p["type"].as_str().unwrap().ends_with("invalid-query"),
        "{p}"
    );
    let (st, p) = call(
        &a,
        "GET",
        &format!("{base}/v1/spatial/sphere?x=0&y=0&z=1e200&r=1.5e200"),
        None,
    );
    assert_eq!(st, 422, "{p}");

    // A box out to ±1e308 finds every body a box around the scene finds.
    let found = |lo: f64, hi: f64| {
        let q = json!({"min": [lo, lo, lo], "max": [hi, hi, hi], "detail": "bodies"});
        let (st, v) = call(&a, "POST", &format!("{base}/v1/spatial/box"), Some(&q));
        assert_eq!(st, 200, "{v}");
        assert_no_null(&v, "a box query");
        let mut ids: Vec<u64> = v["bodies"]
            .as_array()
            .unwrap()
            .iter()
            .map(|b| b["id"].as_u64().unwrap())
            .collect();
        ids.sort_unstable();
        ids
    };
    let near = found(-10.0, 10.0);
    assert!(near.len() >= 9, "{near:?}");
    assert_eq!(found(-1e308, 1e308), near);
    let (st, v) = call(
        &a,
        "GET",
        &format!("{base}/v1/spatial/nearest?x=0&y=0&z=1e9"),
        None,
    );
    assert_eq!(st, 200, "{v}");
    assert_no_null(&v, "a far nearest query");

    // An axis of huge components is a direction like any other.
    let rotate = json!({"op": "rotate", "axis": [-6e16, 1.5e158, -6.6e15], "angle_deg": 10});
    let url = format!("{base}/v1/bodies/{table}/transform");
    let (st, v) = call(&a, "POST", &url, Some(&rotate));
    assert_eq!(st, 200, "{v}");
    let (_, list) = call(&a, "GET", &format!("{base}/v1/bodies"), None);
    assert_no_null(&list, "GET /v1/bodies after the rotation");
}

#[test]
fn a_patch_that_changes_nothing_is_no_revision_and_no_change() {
    let s = Server::start(&["--memory", "--demo"]);
    let a = agent(Duration::from_secs(30));
    let base = s.base.clone();
    let table = body_id(&a, &base, "table");
    let url = format!("{base}/v1/bodies/{table}");
    let before = revision(&a, &base);
    let (_, body) = call(&a, "GET", &url, None);

    let same_name = json!({"name": "table"});
    for patch in [json!({}), same_name] {
        let (st, v) = call(&a, "PATCH", &url, Some(&patch));
        assert_eq!(st, 200, "{patch}: {v}");
        assert_eq!(v["revision"], before, "{patch}: {v}");
        assert_eq!(revision(&a, &base), before, "{patch}");
    }
    let (_, changes) = call(
        &a,
        "GET",
        &format!("{base}/v1/world/changes?since={before}"),
        None,
    );
    assert_eq!(changes["changes"], json!([]), "{changes}");
    assert_eq!(call(&a, "GET", &url, None).1, body);

    // Still refused where a write would be: an unknown body.
    let (st, _) = call(
        &a,
        "PATCH",
        &format!("{base}/v1/bodies/999999"),
        Some(&json!({})),
    );
    assert_eq!(st, 404);
    // And a real change is a revision.
    let (st, v) = call(&a, "PATCH", &url, Some(&json!({"name": "desk"})));
    assert_eq!(st, 200);
    assert_eq!(v["revision"], before + 1);
}

#[test]
fn names_that_would_not_read_back_as_written_are_refused() {
    let s = Server::start(&["--memory", "--demo"]);
    let a = agent(Duration::from_secs(30));
    let base = s.base.clone();
    let before = revision(&a, &base);

    let long = "n".repeat(129);
    for query in ["%FF", "a%00b", long.as_str()] {
        let (st, p) = call(&a, "GET", &format!("{base}/v1/bodies?name={query}"), None);
        assert_eq!(st, 400, "?name={query}: {p}");
    }
    let bad = [
        "right\u{202E}to-left",  // a bidi override
        "zero\u{200B}width",     // a zero-width space
        "e\u{0301}tagere",       // not NFC: NFC is "étagere"
        "line\u{2028}separator", // a line separator
        long.as_str(),
    ];
    for name in bad {
        let req = json!({"name": name, "shape": {"type": "box", "size": [1, 1, 1]}});
        let (st, p) = call(&a, "POST", &format!("{base}/v1/bodies"), Some(&req));
        assert_eq!(st, 422, "{name:?}: {p}");
        assert!(p["type"].as_str().unwrap().ends_with("invalid-name"), "{p}");
    }
    assert_eq!(revision(&a, &base), before);
    // The NFC spelling of the same name is fine, and a filter in another normalization
    // form finds it.
    let req = json!({"name": "\u{00E9}tagere", "shape": {"type": "box", "size": [1, 1, 1]}});
    let (st, made) = call(&a, "POST", &format!("{base}/v1/bodies"), Some(&req));
    assert_eq!(st, 201, "{made}");
    let (st, found) = call(
        &a,
        "GET",
        &format!("{base}/v1/bodies?name=e%CC%81tagere"),
        None,
    );
    assert_eq!(st, 200, "{found}");
    assert_eq!(found["bodies"][0]["id"], made["id"], "{found}");
}

// ------------------------------------------------------------------ damaged directories

/// The folder of a data directory that holds its snapshots.
const SNAPSHOTS: &str = "snapshots";

/// What the writers of a killed server were told.
struct Acked {
    /// Name and id of every acknowledged body.
    bodies: Vec<(String, u64)>,
    /// The highest revision acknowledged.
    revision: u64,
}

/// A data directory written by the real server, with two snapshots, then SIGKILLed with
/// writes after the newest snapshot still in the write-ahead log.
fn killed_directory(dir: &Path) -> Acked {
    let s = Server::start(&["--data", &data_arg(dir)]);
    let a = agent(Duration::from_secs(30));
    let mut acked = Acked {
        bodies: Vec::new(),
        revision: 0,
    };
    for i in 0..120 {
        if i == 40 || i == 80 {
            let (st, v) = call(&a, "POST", &format!("{}/v1/admin/snapshot", s.base), None);
            assert_eq!(st, 200, "{v}");
        }
        let name = format!("b{i}");
        let req = json!({"name": name, "shape": {"type": "box", "size": [1, 1, 1]},
                         "pose": {"position": [i as f64, 0, 0], "rotation": [0, 0, 0, 1]}});
        let (st, v) = call(&a, "POST", &format!("{}/v1/bodies", s.base), Some(&req));
        assert_eq!(st, 201, "{v}");
        acked.bodies.push((name, v["id"].as_u64().unwrap()));
        acked.revision = acked.revision.max(v["revision"].as_u64().unwrap());
    }
    s.kill();
    acked
}

fn snapshots(dir: &Path) -> Vec<PathBuf> {
    let mut s: Vec<PathBuf> = std::fs::read_dir(dir.join(SNAPSHOTS))
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e == "snap"))
        .collect();
    s.sort();
    s
}

fn flip_byte(path: &Path, at: u64) {
    let mut bytes = std::fs::read(path).unwrap();
    let i = (at as usize).min(bytes.len() - 1);
    bytes[i] ^= 0x5a;
    std::fs::write(path, bytes).unwrap();
}

/// Copies the files of `from` into `to`, and its folders' files, recursively.
fn copy_dir(from: &Path, to: &Path) {
    for e in std::fs::read_dir(from).unwrap() {
        let p = e.unwrap().path();
        let into = to.join(p.file_name().unwrap());
        if p.is_dir() {
            std::fs::create_dir_all(&into).unwrap();
            copy_dir(&p, &into);
        } else if p.is_file() {
            std::fs::copy(&p, into).unwrap();
        }
    }
}

/// The server on `dir` either holds every acknowledged write (and then issues only new
/// ids and revisions) or refuses to start, naming revisions. Returns whether it started.
fn recovers_or_refuses(dir: &Path, acked: &Acked, case: &str, extra: &[&str]) -> bool {
    let data = data_arg(dir);
    let mut args = vec!["--data", data.as_str()];
    args.extend_from_slice(extra);
    match Server::try_start(&args) {
        Ok(s) => {
            let a = agent(Duration::from_secs(30));
            let rev = revision(&a, &s.base);
            assert!(
                rev >= acked.revision,
                "{case}: started at revision {rev}, behind the acknowledged {}",
                acked.revision
            );
            let max_id = acked.bodies.iter().map(|b| b.1).max().unwrap();
            if extra.is_empty() {
                for (name, id) in &acked.bodies {
                    assert_eq!(body_id(&a, &s.base, name), *id, "{case}: body {name}");
                }
            }
            let req = json!({"name": "after", "shape": {"type": "box", "size": [1, 1, 1]}});
            let (st, v) = call(&a, "POST", &format!("{}/v1/bodies", s.base), Some(&req));
            assert_eq!(st, 201, "{case}: {v}");
            let id = v["id"].as_u64().unwrap();
            assert!(
                id > max_id,
                "{case}: id {id} reissued (acknowledged up to {max_id})"
            );
            assert!(
                v["revision"].as_u64().unwrap() > acked.revision,
                "{case}: {v}"
            );
            true
        }
        Err(output) => {
            assert!(
                output.contains("revision"),
                "{case}: a refusal must say what is missing:\n{output}"
            );
            false
        }
    }
}

#[test]
fn a_damaged_data_directory_recovers_every_acknowledged_write_or_refuses() {
    let template = tempfile::tempdir().unwrap();
    let acked = killed_directory(template.path());
    let wal = "journal.db-wal";
    let wal_len = std::fs::metadata(template.path().join(wal))
        .map(|m| m.len())
        .unwrap_or(0);
    assert!(
        wal_len > 0,
        "the killed server left its latest writes in the WAL"
    );
    let snaps: Vec<PathBuf> = snapshots(template.path())
        .iter()
        .map(|p| Path::new(SNAPSHOTS).join(p.file_name().unwrap()))
        .collect();
    assert_eq!(snaps.len(), 2, "{snaps:?}");

    type Damage = Box<dyn Fn(&Path)>;
    let cases: Vec<(&str, Damage)> = vec![
        ("nothing", Box::new(|_: &Path| {})),
        (
            "WAL deleted",
            Box::new(move |d: &Path| {
                std::fs::remove_file(d.join(wal)).unwrap();
                let _ = std::fs::remove_file(d.join("journal.db-shm"));
            }),
        ),
        (
            "WAL truncated",
            Box::new(move |d: &Path| {
                let f = std::fs::OpenOptions::new()
                    .write(true)
                    .open(d.join(wal))
                    .unwrap();
                f.set_len(wal_len / 2).unwrap();
            }),
        ),
        (
            "WAL flipped",
            Box::new(move |d: &Path| flip_byte(&d.join(wal), wal_len / 2)),
        ),
        (
            "newest snapshot flipped",
            Box::new({
                let s = snaps[1].clone();
                move |d: &Path| flip_byte(&d.join(&s), 100)
            }),
        ),
        (
            "older snapshot flipped",
            Box::new({
                let s = snaps[0].clone();
                move |d: &Path| flip_byte(&d.join(&s), 100)
            }),
        ),
        (
            "both snapshots truncated",
            Box::new({
                let s = snaps.clone();
                move |d: &Path| {
                    for s in &s {
                        std::fs::write(d.join(s), b"").unwrap();
                    }
                }
            }),
        ),
        (
            "WAL deleted and the newest snapshot flipped",
            Box::new({
                let s = snaps[1].clone();
                move |d: &Path| {
                    std::fs::remove_file(d.join(wal)).unwrap();
                    flip_byte(&d.join(&s), 100);
                }
            }),
        ),
        (
            "reached marker deleted",
            Box::new(|d: &Path| std::fs::remove_file(d.join("reached")).unwrap()),
        ),
    ];
    let mut refused = Vec::new();
    for (case, damage) in &cases {
        let dir = tempfile::tempdir().unwrap();
        copy_dir(template.path(), dir.path());
        damage(dir.path());
        if !recovers_or_refuses(dir.path(), &acked, case, &[]) {
            refused.push(*case);
            // The operator's way out: resume past the loss, never behind the
            // acknowledged revision and never with an acknowledged id.
            assert!(
                recovers_or_refuses(dir.path(), &acked, case, &["--accept-loss"]),
                "{case}: --accept-loss did not start"
            );
        }
    }
    eprintln!("refused at start: {refused:?}");
    // A lost WAL took acknowledged writes: the start must have been refused (as it must
    // when it took the newest snapshot's proof along with it).
    assert!(refused.contains(&"WAL deleted"), "refused: {refused:?}");
    assert!(!refused.contains(&"nothing"), "refused: {refused:?}");
}

#[test]
fn a_lost_wal_is_named_with_both_revisions() {
    let dir = tempfile::tempdir().unwrap();
    let acked = killed_directory(dir.path());
    std::fs::remove_file(dir.path().join("journal.db-wal")).unwrap();
    let _ = std::fs::remove_file(dir.path().join("journal.db-shm"));
    let output = match Server::try_start(&["--data", &data_arg(dir.path())]) {
        Ok(_) => panic!("a directory that lost acknowledged writes was started"),
        Err(output) => output,
    };
    assert!(
        output.contains(&format!("revision {} was acknowledged", acked.revision)),
        "{output}"
    );
    assert!(output.contains("--accept-loss"), "{output}");
    let (st, text) = process::run(&["check", "--data", &data_arg(dir.path())]);
    assert!(
        !st.success(),
        "winged check passed a directory behind its marker: {text}"
    );
}
