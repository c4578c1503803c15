//! Bearer tokens over real HTTP: every route the contract lists refuses a missing token
//! (401) and a token of too low a role (403) before it does anything; a read token
//! reads; a write token writes; admin routes want an admin token.

#[path = "support/http.rs"]
mod support;

use std::sync::Arc;

use serde_json::{Value, json};
use support::TestServer;
use winged::server::auth::Tokens;
use winged::server::{Options, build};

const READ: &str = "read-token-0123456789";
const WRITE: &str = "write-token-0123456789";
const ADMIN: &str = "admin-token-0123456789";

/// Routes anyone may call.
const OPEN: &[&str] = &["/healthz", "/readyz", "/openapi.json"];

fn server() -> TestServer {
    let tokens = Tokens::from_sources(
        &[format!("read:{READ}"), format!("write:{WRITE}")],
        Some(&format!("admin:{ADMIN}")),
        None,
    )
    .expect("tokens");
    TestServer::with_app(move || {
        let options = Options {
            tokens: Arc::new(tokens),
            ..Options::default()
        };
        let world = winged::server::demo::demo_world().expect("the demo world");
        build(world, winged::server::actor::InMemory, Vec::new(), options).expect("the server")
    })
}

/// Every (METHOD, path template) in the contract.
fn operations() -> Vec<(String, String)> {
    let text = std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/proto/openapi.yaml"))
        .expect("the contract");
    let doc: Value = serde_norway::from_str(&text).expect("YAML");
    let mut ops = Vec::new();
    for (path, item) in doc["paths"].as_object().expect("paths") {
        for method in ["get", "put", "post", "patch", "delete"] {
            if item.get(method).is_some() {
                ops.push((method.to_uppercase(), path.clone()));
            }
        }
    }
    ops
}

fn call(
    s: &TestServer,
    method: &str,
    path: &str,
    token: Option<&str>,
) -> (u16, String, Option<String>) {
    let agent = s.agent();
    let url = s.url(path);
    let auth = token.map(|t| format!("Bearer {t}"));
    let res = match method {
        "GET" => {
            let mut r = agent.get(&url);
            if let Some(a) = &auth {
                r = r.header("Authorization", a);
            }
            r.call()
        }
        "DELETE" => {
            let mut r = agent.delete(&url);
            if let Some(a) = &auth {
                r = r.header("Authorization", a);
            }
            r.call()
        }
        m => {
            let mut r = match m {
                "POST" => agent.post(&url),
                "PUT" => agent.put(&url),
                _ => agent.patch(&url),
            };
            if let Some(a) = &auth {
                r = r.header("Authorization", a);
            }
            r.send_json(json!({}))
        }
    };
    let mut res = res.expect("the server answers");
    let status = res.status().as_u16();
    let challenge = res
        .headers()
        .get("www-authenticate")
        .and_then(|v| v.to_str().ok())
        .map(str::to_owned);
    let text = res.body_mut().read_to_string().unwrap_or_default();
    (status, text, challenge)
}

fn revision(s: &TestServer) -> u64 {
    let (status, text, _) = call(s, "GET", "/v1/world", Some(READ));
    assert_eq!(status, 200, "{text}");
    serde_json::from_str::<Value>(&text).expect("JSON")["revision"]
        .as_u64()
        .expect("a revision")
}

#[test]
fn every_guarded_route_refuses_missing_and_too_weak_tokens() {
    let s = server();
    let cube = {
        let (_, text, _) = call(&s, "GET", "/v1/bodies?name=cube", Some(READ));
        let v: Value = serde_json::from_str(&text).expect("JSON");
        v["bodies"][0]["id"].as_u64().expect("the demo cube")
    };
    let before = revision(&s);
    let ops = operations();
    assert!(
        ops.len() > 25,
        "the contract lists {} operations",
        ops.len()
    );
    let mut writes = 0;
    for (method, template) in ops {
        if OPEN.contains(&template.as_str()) {
            let (status, text, _) = call(&s, &method, &template, None);
            assert_eq!(status, 200, "{method} {template} is open: {text}");
            continue;
        }
        let path = template
            .replace("{id}", &cube.to_string())
            .replace("{name}", "eye")
            .replace("/v1/world/changes", "/v1/world/changes?since=0");
        if template == "/v1/world/events" {
            // The stream never ends; its guard is checked without a token only.
            let (status, _, challenge) = call(&s, &method, &path, None);
            assert_eq!(status, 401);
            assert!(challenge.is_some());
            continue;
        }
        let needs = if template.starts_with("/v1/admin") {
            "admin"
        } else if method == "GET"
            || template == "/v1/appearance"
            || template == "/v1/camera-solution"
            || template == "/v1/recognition"
            || template.starts_with("/v1/spatial/")
        {
            // POST /v1/appearance draws, POST /v1/spatial/* query, POST
            // /v1/camera-solution solves (storing needs write, checked below) and POST
            // /v1/recognition recognizes (updating needs write, checked below); they
            // change nothing and need only the read role.
            "read"
        } else {
            "write"
        };
        // No token, a malformed header, an unknown token: 401 with a challenge.
        for token in [None, Some("not-a-token-at-all")] {
            let (status, text, challenge) = call(&s, &method, &path, token);
            assert_eq!(status, 401, "{method} {path} with {token:?}: {text}");
            assert!(
                challenge
                    .as_deref()
                    .is_some_and(|c| c.starts_with("Bearer")),
                "{method} {path}: {challenge:?}"
            );
            let p: Value = serde_json::from_str(&text).expect("problem JSON");
            assert_eq!(p["type"], "urn:winged:problem:unauthorized");
        }
        // A token below the route's role: 403.
        let weaker: &[&str] = match needs {
            "admin" => &[READ, WRITE],
            "write" => &[READ],
            _ => &[],
        };
        for token in weaker {
            let (status, text, _) = call(&s, &method, &path, Some(token));
            assert_eq!(status, 403, "{method} {path}: {text}");
            let p: Value = serde_json::from_str(&text).expect("problem JSON");
            assert_eq!(p["type"], "urn:winged:problem:forbidden");
            assert!(p["detail"].as_str().unwrap().contains(needs), "{p}");
        }
        // The right role gets past the guard (the empty body may still be refused).
        let enough = match needs {
            "admin" => ADMIN,
            "write" => WRITE,
            _ => READ,
        };
        let (status, text, _) = call(&s, &method, &path, Some(enough));
        assert!(
            status != 401 && status != 403,
            "{method} {path}: {status} {text}"
        );
        if method != "GET" {
            writes += 1;
        }
    }
    assert!(writes >= 14, "only {writes} write routes were tried");
    // Only writes that got past the guard changed the world (some accept an empty
    // body: dual, evert, copy, the deletes); each is in the change list.
    let (_, text, _) = call(
        &s,
        "GET",
        &format!("/v1/world/changes?since={before}"),
        Some(READ),
    );
    let v: Value = serde_json::from_str(&text).expect("JSON");
    assert_eq!(v["resync"], false, "{v}");
    let applied = v["changes"].as_array().map_or(0, |c| c.len() as u64);
    assert!(applied > 0);
    assert_eq!(revision(&s), before + applied);
}

#[test]
fn each_role_does_what_it_may() {
    let s = server();
    let agent = s.agent();
    let create = |token: &str| {
        agent
            .post(&s.url("/v1/bodies"))
            .header("Authorization", format!("Bearer {token}"))
            .send_json(json!({"name": format!("box-{token}"), "shape": {"type": "box", "size": [1, 1, 1]}}))
            .expect("the server answers")
            .status()
            .as_u16()
    };
    let before = revision(&s);
    assert_eq!(create(READ), 403);
    assert_eq!(revision(&s), before, "a refused write changes nothing");
    assert_eq!(create(WRITE), 201);
    assert_eq!(create(ADMIN), 201);
    // Admin routes: write is not enough; admin passes the guard (an in-memory world has
    // nowhere to write a snapshot: 409).
    let snap = |token: &str| {
        agent
            .post(&s.url("/v1/admin/snapshot"))
            .header("Authorization", format!("Bearer {token}"))
            .send_empty()
            .expect("the server answers")
            .status()
            .as_u16()
    };
    assert_eq!(snap(WRITE), 403);
    assert_eq!(snap(ADMIN), 409);
    // The scheme is case-insensitive; the token is not.
    let status = agent
        .get(&s.url("/v1/world"))
        .header("Authorization", format!("bearer {READ}"))
        .call()
        .expect("answers")
        .status()
        .as_u16();
    assert_eq!(status, 200);
    let status = agent
        .get(&s.url("/v1/world"))
        .header("Authorization", format!("Bearer {}", READ.to_uppercase()))
        .call()
        .expect("answers")
        .status()
        .as_u16();
    assert_eq!(status, 401);
}

#[test]
fn a_read_token_solves_and_recognizes_but_only_a_write_token_stores_or_updates() {
    use winged::model::{Camera, Intrinsics};
    let s = server();
    let agent = s.agent();
    let k = Intrinsics::new(640, 480, 500.0, 500.0, 320.0, 240.0).expect("intrinsics");
    let eye = Camera::look_at(
        glam::DVec3::new(3.0, -2.0, 2.0),
        glam::DVec3::ZERO,
        glam::DVec3::Z,
        k,
    )
    .expect("a camera");
    let correspondences: Vec<Value> = (0..12)
        .map(|i| {
            let p = glam::DVec3::new(
                (i % 3) as f64 * 0.4 - 0.4,
                (i / 3 % 2) as f64 * 0.5 - 0.25,
                (i / 6) as f64 * 0.3 + (i % 2) as f64 * 0.1,
            );
            let px = eye.project(p).expect("in front");
            json!({"pixel": px.to_array(), "point": p.to_array()})
        })
        .collect();
    let solve = |token: &str, store: bool| {
        let mut body = json!({
            "intrinsics": {"width": 640, "height": 480, "fx": 500.0, "fy": 500.0, "cx": 320.0, "cy": 240.0},
            "correspondences": correspondences,
        });
        if store {
            body["store_as"] = json!("solved");
        }
        let mut res = agent
            .post(&s.url("/v1/camera-solution"))
            .header("Authorization", format!("Bearer {token}"))
            .send_json(body)
            .expect("the server answers");
        let status = res.status().as_u16();
        let text = res.body_mut().read_to_string().unwrap_or_default();
        (status, text)
    };
    let before = revision(&s);
    let (status, text) = solve(READ, false);
    assert_eq!(status, 200, "{text}");
    let (status, text) = solve(READ, true);
    assert_eq!(status, 403, "{text}");
    let p: Value = serde_json::from_str(&text).expect("problem JSON");
    assert_eq!(p["type"], "urn:winged:problem:forbidden");
    assert!(p["detail"].as_str().unwrap().contains("write"), "{p}");
    assert_eq!(revision(&s), before, "nothing was stored");
    let (status, text) = solve(WRITE, true);
    assert_eq!(status, 200, "{text}");
    assert_eq!(revision(&s), before + 1);
    // Recognition reads; "update" writes, and needs the write role.
    let blank = support::blank_png_base64(640, 480);
    let camera = json!({
        "pose": {"position": eye.pose.position.to_array(), "rotation": eye.pose.rotation.to_array()},
        "intrinsics": {"width": 640, "height": 480, "fx": 500.0, "fy": 500.0, "cx": 320.0, "cy": 240.0},
    });
    let recognize = |token: &str, update: bool| {
        let mut res = agent
            .post(&s.url("/v1/recognition"))
            .header("Authorization", format!("Bearer {token}"))
            .send_json(json!({"camera": camera, "image": blank, "update": update}))
            .expect("the server answers");
        let status = res.status().as_u16();
        let text = res.body_mut().read_to_string().unwrap_or_default();
        (status, text)
    };
    let before = revision(&s);
    let (status, text) = recognize(READ, false);
    assert_eq!(status, 200, "{text}");
    let (status, text) = recognize(READ, true);
    assert_eq!(status, 403, "{text}");
    assert!(text.contains("write"), "{text}");
    let (status, text) = recognize(WRITE, true);
    assert_eq!(status, 200, "{text}");
    assert_eq!(
        revision(&s),
        before,
        "nothing moved, so nothing was written"
    );
}
