//! Crash safety of the real binary: clients write continuously, the server is killed
//! with SIGKILL at a moment nobody chose, and a restart on the same data directory must
//! hold every acknowledged write, continue the revisions, never reuse an id, and pass
//! the validator on every body. Several rounds on one directory.

#[path = "support/process.rs"]
mod process;

use std::collections::BTreeMap;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, Mutex};
use std::thread;
use std::time::{Duration, SystemTime, UNIX_EPOCH};

use process::{Server, agent, check_data};
use serde_json::{Value, json};

const ROUNDS: usize = 4;
const WRITERS: usize = 6;

/// What the clients were told was done.
#[derive(Default)]
struct Acked {
    /// Body name → id, for every acknowledged creation.
    bodies: BTreeMap<String, u64>,
    /// Body id → the x of every pose sent to it, in order, and how many of them (a
    /// prefix) were acknowledged.
    poses: BTreeMap<u64, (Vec<f64>, usize)>,
    /// The highest revision any answer gave.
    revision: u64,
    /// The highest id any answer gave.
    max_id: u64,
}

/// A moment in `lo..hi` ms that nobody chose.
fn random_ms(lo: u64, hi: u64, salt: u64) -> u64 {
    let nanos = SystemTime::now()
        .duration_since(UNIX_EPOCH)
        .map_or(0, |d| d.subsec_nanos() as u64);
    let mixed =
        (nanos ^ salt.wrapping_mul(0x9E37_79B9_7F4A_7C15)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    lo + (mixed >> 11) % (hi - lo)
}

fn post(agent: &ureq::Agent, url: &str, body: &Value) -> Option<(u16, Value)> {
    let mut res = agent.post(url).send_json(body).ok()?;
    let status = res.status().as_u16();
    let v = res.body_mut().read_json::<Value>().ok()?;
    Some((status, v))
}

fn patch(agent: &ureq::Agent, url: &str, body: &Value) -> Option<(u16, Value)> {
    let mut res = agent.patch(url).send_json(body).ok()?;
    let status = res.status().as_u16();
    let v = res.body_mut().read_json::<Value>().ok()?;
    Some((status, v))
}

/// One client: creates bodies and moves them until the server goes away.
fn writer(base: String, round: usize, w: usize, acked: Arc<Mutex<Acked>>, stop: Arc<AtomicBool>) {
    let http = agent(Duration::from_secs(10));
    let mut n = 0;
    while !stop.load(Ordering::Relaxed) {
        let name = format!("r{round}-w{w}-{n}");
        n += 1;
        let req = json!({"name": name, "shape": {"type": "box", "size": [1, 1, 1]}});
        let Some((status, v)) = post(&http, &format!("{base}/v1/bodies"), &req) else {
            return;
        };
        assert_eq!(status, 201, "{v}");
        let id = v["id"].as_u64().expect("an id");
        let revision = v["revision"].as_u64().expect("a revision");
        {
            let mut a = acked.lock().unwrap();
            a.bodies.insert(name, id);
            a.revision = a.revision.max(revision);
            a.max_id = a.max_id.max(id);
            a.poses.insert(id, (Vec::new(), 0));
        }
        for k in 0..3 {
            let x = (round * 1000 + w * 100 + n * 3 + k) as f64;
            acked.lock().unwrap().poses.get_mut(&id).unwrap().0.push(x);
            let pose = json!({"pose": {"position": [x, 0, 0], "rotation": [0, 0, 0, 1]}});
            let Some((status, v)) = patch(&http, &format!("{base}/v1/bodies/{id}"), &pose) else {
                return;
            };
            assert_eq!(status, 200, "{v}");
            let mut a = acked.lock().unwrap();
            a.revision = a.revision.max(v["revision"].as_u64().expect("a revision"));
            let entry = a.poses.get_mut(&id).unwrap();
            entry.1 = entry.0.len();
        }
    }
}

fn get(http: &ureq::Agent, url: &str) -> (u16, Value) {
    let mut res = http.get(url).call().expect("the server answers");
    let status = res.status().as_u16();
    (status, res.body_mut().read_json().expect("JSON"))
}

#[test]
fn acknowledged_writes_survive_sigkill_and_revisions_continue() {
    let dir = tempfile::tempdir().expect("a temporary directory");
    let data = dir.path().join("world");
    let data_arg = data.display().to_string();
    let acked = Arc::new(Mutex::new(Acked::default()));
    let http = agent(Duration::from_secs(30));
    for round in 0..ROUNDS {
        // Small snapshot interval, so some rounds recover from a snapshot plus journal.
        let server = Server::start(&["--data", &data_arg, "--snapshot-every", "150"]);
        let base = server.base.clone();

        // Everything acknowledged before is here, exactly.
        {
            let a = acked.lock().unwrap();
            let (_, world) = get(&http, &format!("{base}/v1/world"));
            let revision = world["revision"].as_u64().unwrap();
            assert!(
                revision >= a.revision,
                "round {round}: revision {revision} is behind the acknowledged {}",
                a.revision
            );
            for (name, id) in &a.bodies {
                let (status, body) = get(&http, &format!("{base}/v1/bodies/{id}"));
                assert_eq!(
                    status, 200,
                    "round {round}: acknowledged body {name} ({id}) is lost"
                );
                assert_eq!(body["name"], *name);
                let (sent, ok) = &a.poses[id];
                let x = body["pose"]["position"][0].as_f64().unwrap();
                // The last acknowledged pose, or one sent after it whose answer the
                // kill cut off; never an older one.
                let allowed: Vec<f64> = if *ok == 0 {
                    std::iter::once(0.0).chain(sent.iter().copied()).collect()
                } else {
                    sent[ok - 1..].to_vec()
                };
                assert!(
                    allowed.contains(&x),
                    "round {round}: body {id} is at x = {x}; acknowledged poses {:?}, sent {sent:?}",
                    &sent[..*ok]
                );
            }
        }

        let stop = Arc::new(AtomicBool::new(false));
        let writers: Vec<_> = (0..WRITERS)
            .map(|w| {
                let (base, acked, stop) = (base.clone(), acked.clone(), stop.clone());
                thread::spawn(move || writer(base, round, w, acked, stop))
            })
            .collect();
        thread::sleep(Duration::from_millis(random_ms(300, 1500, round as u64)));
        server.kill();
        stop.store(true, Ordering::Relaxed);
        for w in writers {
            w.join().expect("a writer");
        }

        // The validator passes on every body of the directory as the kill left it.
        let report = check_data(&data);
        assert!(report.contains(" 0 invalid"), "{report}");
    }

    // A last start: writes continue after the highest acknowledged revision, and new
    // ids are new.
    let server = Server::start(&["--data", &data_arg]);
    let a = acked.lock().unwrap();
    assert!(
        a.bodies.len() > 20,
        "the writers made too little: {}",
        a.bodies.len()
    );
    let (status, made) = post(
        &http,
        &format!("{}/v1/bodies", server.base),
        &json!({"shape": {"type": "box", "size": [1, 1, 1]}}),
    )
    .expect("the server answers");
    assert_eq!(status, 201);
    assert!(made["revision"].as_u64().unwrap() > a.revision);
    assert!(made["id"].as_u64().unwrap() > a.max_id);
    // The change history survived the kills: the last writes are still listed, in
    // order, ending at the world's revision.
    let since = a.revision - 10;
    let (status, changes) = get(
        &http,
        &format!("{}/v1/world/changes?since={since}", server.base),
    );
    assert_eq!(status, 200);
    assert_eq!(changes["resync"], false, "{changes}");
    let revisions: Vec<u64> = changes["changes"]
        .as_array()
        .expect("changes")
        .iter()
        .map(|c| c["revision"].as_u64().expect("a revision"))
        .collect();
    let now = made["revision"].as_u64().unwrap();
    assert_eq!(revisions, (since + 1..=now).collect::<Vec<_>>());
    // One process per data directory: the running server holds it.
    let (status, out) = process::run(&["check", "--data", &data_arg]);
    assert!(!status.success());
    assert!(out.contains("in use"), "{out}");
    // A clean stop writes a final snapshot.
    let status = server.stop();
    assert!(status.success(), "{status:?}");
    let snaps = std::fs::read_dir(data.join("snapshots"))
        .expect("a snapshot directory")
        .count();
    assert!(snaps >= 1);
}
