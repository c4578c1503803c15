//! The API contract: `proto/openapi.yaml` against the router and the running server.
//!
//! - every route in `src/server/api.rs` is an operation of the contract and back;
//! - the contract is well-formed (references resolve, only supported schema keywords,
//!   discriminators consistent, path parameters declared);
//! - `GET /openapi.json` serves the same document as the YAML file;
//! - a real server on an ephemeral port, driven over HTTP through every operation with
//!   valid and invalid requests, gives only declared status codes, and every answer's
//!   body matches the declared media type and schema. Valid requests conform to the
//!   request schemas; malformed ones the server refuses with 400 are refused by the
//!   request schemas too. Every write answers the revision after it, and refused writes
//!   leave the revision as it was.

#[path = "support/contract/mod.rs"]
mod contract_support;

use std::cell::RefCell;
use std::collections::{BTreeMap, BTreeSet};

use serde_json::{Value, json};

use contract_support::routes::routes;
use contract_support::schema::Validator;
use contract_support::server::{Http, Reply, Send, TestServer};

const SPEC_YAML: &str = include_str!("../proto/openapi.yaml");
const ROUTER_SOURCE: &str = include_str!("../src/server/api/mod.rs");
const HTTP_METHODS: &[&str] = &[
    "get", "put", "post", "delete", "options", "head", "patch", "trace",
];

fn spec() -> Value {
    serde_norway::from_str(SPEC_YAML).expect("proto/openapi.yaml is YAML")
}

/// `(METHOD, PATH)` of every operation in the contract.
fn spec_operations(doc: &Value) -> BTreeSet<(String, String)> {
    let paths = doc["paths"].as_object().expect("paths is an object");
    let mut ops = BTreeSet::new();
    for (path, item) in paths {
        for method in item.as_object().expect("a path item is an object").keys() {
            if HTTP_METHODS.contains(&method.as_str()) {
                ops.insert((method.to_uppercase(), path.clone()));
            }
        }
    }
    ops
}

/// Routes served that are not part of the API: the browser viewer's page and files
/// (`src/server/viewer/`, `clients/viewer/README.md`), HTML and scripts for a browser
/// rather than operations for a client.
const NOT_API: &[(&str, &str)] = &[("GET", "/"), ("GET", "/viewer/{file}")];

#[test]
fn every_served_route_is_in_the_contract_and_back() {
    let all: BTreeSet<(String, String)> = routes(ROUTER_SOURCE)
        .expect("the router's routes can be read")
        .into_iter()
        .collect();
    for (method, path) in NOT_API {
        assert!(
            all.contains(&(method.to_string(), path.to_string())),
            "{method} {path} is listed as served outside the API but is not served"
        );
    }
    let served: BTreeSet<(String, String)> = all
        .into_iter()
        .filter(|(m, p)| !NOT_API.contains(&(m.as_str(), p.as_str())))
        .collect();
    assert!(
        served.len() > 10,
        "suspiciously few routes read from api.rs: {served:?}"
    );
    let declared = spec_operations(&spec());
    let undeclared: Vec<_> = served.difference(&declared).collect();
    let unserved: Vec<_> = declared.difference(&served).collect();
    assert!(
        undeclared.is_empty() && unserved.is_empty(),
        "routes served but missing from proto/openapi.yaml: {undeclared:?}\n\
         operations in proto/openapi.yaml that the router does not serve: {unserved:?}"
    );
}

/// Every schema the document uses, with where it is.
fn schemas_in(doc: &Value) -> Vec<(String, &Value)> {
    let mut out = Vec::new();
    if let Some(s) = doc
        .pointer("/components/schemas")
        .and_then(Value::as_object)
    {
        for (name, schema) in s {
            out.push((format!("#/components/schemas/{name}"), schema));
        }
    }
    for section in ["responses", "requestBodies"] {
        if let Some(s) = doc
            .pointer(&format!("/components/{section}"))
            .and_then(Value::as_object)
        {
            for (name, r) in s {
                for (mt, m) in r["content"].as_object().into_iter().flatten() {
                    out.push((
                        format!("#/components/{section}/{name}/content/{mt}"),
                        &m["schema"],
                    ));
                }
            }
        }
    }
    if let Some(s) = doc
        .pointer("/components/parameters")
        .and_then(Value::as_object)
    {
        for (name, p) in s {
            out.push((format!("#/components/parameters/{name}"), &p["schema"]));
        }
    }
    for (path, item) in doc["paths"].as_object().into_iter().flatten() {
        for (i, p) in item["parameters"]
            .as_array()
            .into_iter()
            .flatten()
            .enumerate()
        {
            if p.get("$ref").is_some() {
                continue;
            }
            out.push((format!("{path} parameter {i}"), &p["schema"]));
        }
        for (method, op) in item.as_object().into_iter().flatten() {
            if !HTTP_METHODS.contains(&method.as_str()) {
                continue;
            }
            let at = format!("{} {path}", method.to_uppercase());
            for (i, p) in op["parameters"]
                .as_array()
                .into_iter()
                .flatten()
                .enumerate()
            {
                if p.get("$ref").is_some() {
                    continue;
                }
                out.push((format!("{at} parameter {i}"), &p["schema"]));
            }
            for (mt, m) in op
                .pointer("/requestBody/content")
                .and_then(Value::as_object)
                .into_iter()
                .flatten()
            {
                out.push((format!("{at} request {mt}"), &m["schema"]));
            }
            for (code, r) in op["responses"].as_object().into_iter().flatten() {
                for (mt, m) in r["content"].as_object().into_iter().flatten() {
                    out.push((format!("{at} {code} {mt}"), &m["schema"]));
                }
            }
        }
    }
    out
}

#[test]
fn the_contract_is_well_formed() {
    let doc = spec();
    let v = Validator::new(&doc);
    let mut problems = Vec::new();
    if !doc["openapi"]
        .as_str()
        .is_some_and(|s| s.starts_with("3.1."))
    {
        problems.push("openapi must be 3.1.x".to_string());
    }
    for (at, schema) in schemas_in(&doc) {
        if schema.is_null() {
            problems.push(format!("{at}: no schema"));
        }
        problems.extend(v.schema_problems(schema, &at));
    }
    let mut operation_ids = BTreeSet::new();
    for (path, item) in doc["paths"].as_object().expect("paths") {
        let in_template: BTreeSet<&str> = path
            .split('/')
            .filter_map(|s| s.strip_prefix('{').and_then(|s| s.strip_suffix('}')))
            .collect();
        for (method, op) in item.as_object().expect("a path item") {
            if !HTTP_METHODS.contains(&method.as_str()) {
                continue;
            }
            let at = format!("{} {path}", method.to_uppercase());
            match op["operationId"].as_str() {
                Some(id) if operation_ids.insert(id.to_string()) => {}
                Some(id) => problems.push(format!("{at}: operationId {id} is used twice")),
                None => problems.push(format!("{at}: no operationId")),
            }
            // Path parameters: declared at the path or the operation, each exactly the
            // template's.
            let mut declared = BTreeSet::new();
            for p in item["parameters"]
                .as_array()
                .into_iter()
                .chain(op["parameters"].as_array())
                .flatten()
            {
                let p = match v.deref(p) {
                    Ok(p) => p,
                    Err(e) => {
                        problems.push(format!("{at}: {e}"));
                        continue;
                    }
                };
                if p["in"] == "path" {
                    if p["required"] != true {
                        problems.push(format!("{at}: path parameter {} not required", p["name"]));
                    }
                    declared.insert(p["name"].as_str().unwrap_or("").to_string());
                }
            }
            let want: BTreeSet<String> = in_template.iter().map(|s| s.to_string()).collect();
            if declared != want {
                problems.push(format!(
                    "{at}: path parameters declared {declared:?}, template has {want:?}"
                ));
            }
            let responses = op["responses"].as_object();
            if responses.is_none_or(|r| r.is_empty()) {
                problems.push(format!("{at}: no responses"));
            }
            for (code, r) in responses.into_iter().flatten() {
                let ok_code = code.len() == 3 && code.parse::<u16>().is_ok_and(|c| c >= 100);
                if !ok_code {
                    problems.push(format!("{at}: response {code:?} is not a status code"));
                    continue;
                }
                let r = match v.deref(r) {
                    Ok(r) => r,
                    Err(e) => {
                        problems.push(format!("{at} {code}: {e}"));
                        continue;
                    }
                };
                if !r["description"].is_string() {
                    problems.push(format!("{at} {code}: no description"));
                }
                // Answers are JSON, except the metrics text, the event stream and
                // drawings (PNG, SVG or JSON).
                let want_media: &[&str] = if !code.starts_with('2') {
                    &["application/problem+json"]
                } else if at.contains("/metrics") {
                    &["application/openmetrics-text"]
                } else if at.contains("/v1/world/events") {
                    &["text/event-stream"]
                } else if at.contains("/image") || at.contains("/v1/appearance") {
                    &["application/json", "image/png", "image/svg+xml"]
                } else if at.contains("/v1/world/mesh") {
                    &["model/gltf-binary"]
                } else if at.contains("/mesh") {
                    &[
                        "application/x-off",
                        "application/x-ply",
                        "model/3mf",
                        "model/gltf-binary",
                        "model/obj",
                        "model/stl",
                    ]
                } else {
                    &["application/json"]
                };
                let media: Vec<&String> = r["content"]
                    .as_object()
                    .into_iter()
                    .flatten()
                    .map(|(k, _)| k)
                    .collect();
                if media != want_media {
                    problems.push(format!(
                        "{at} {code}: media types {media:?}, want {want_media:?}"
                    ));
                }
            }
        }
    }
    assert!(
        problems.is_empty(),
        "proto/openapi.yaml:\n{}",
        problems.join("\n")
    );
}

#[test]
fn the_served_document_is_the_yaml() {
    let server = TestServer::start(winged::model::World::new());
    let http = Http::new(&server.base);
    let r = http.call("GET", "/openapi.json", Send::Nothing);
    assert_eq!(r.status, 200);
    assert_eq!(r.media_type, "application/json");
    assert_eq!(
        r.json(),
        spec(),
        "GET /openapi.json differs from proto/openapi.yaml"
    );
}

// ----- the HTTP exchange checked against the contract ------------------------------

/// Whether the request schema should accept a request the server refuses.
#[derive(Clone, Copy, PartialEq)]
enum Spec {
    /// The request schema refuses it too (malformed input).
    Refuses,
    /// The request schema cannot tell (a semantic refusal).
    Either,
}

struct Contract {
    doc: Value,
    http: Http,
    /// Statuses seen per (METHOD, template).
    seen: RefCell<BTreeMap<(String, String), BTreeSet<u16>>>,
}

impl Contract {
    fn new(base: &str) -> Contract {
        Contract {
            doc: spec(),
            http: Http::new(base),
            seen: RefCell::new(BTreeMap::new()),
        }
    }

    fn v(&self) -> Validator<'_> {
        Validator::new(&self.doc)
    }

    fn operation(&self, method: &str, template: &str) -> &Value {
        let op = &self.doc["paths"][template][method.to_lowercase()];
        assert!(op.is_object(), "{method} {template} is not in the contract");
        op
    }

    fn request_schema(&self, method: &str, template: &str) -> Option<&Value> {
        let body = self.operation(method, template).get("requestBody")?;
        let body = self.v().deref(body).expect("requestBody resolves");
        Some(&body["content"]["application/json"]["schema"])
    }

    /// Sends the request, checks the answer against the contract, records the status.
    fn exchange(&self, method: &str, template: &str, path: &str, body: Send) -> Reply {
        assert!(
            matches_template(template, path),
            "{path} is not an instance of {template}"
        );
        let op = self.operation(method, template);
        let reply = self.http.call(method, path, body);
        let what = format!("{method} {path} answered {}: {}", reply.status, reply.text);
        let declared = op["responses"]
            .get(reply.status.to_string())
            .unwrap_or_else(|| panic!("status {} is not declared: {what}", reply.status));
        let declared = self.v().deref(declared).expect("the response resolves");
        match declared.get("content").and_then(Value::as_object) {
            Some(content) => {
                let media = content.get(&reply.media_type).unwrap_or_else(|| {
                    panic!(
                        "media type {:?} is not declared (declared: {:?}): {what}",
                        reply.media_type,
                        content.keys().collect::<Vec<_>>()
                    )
                });
                // An event stream is checked event by event; other text answers (metrics)
                // as one string.
                let bodies = if reply.media_type.ends_with("json") {
                    vec![reply.json()]
                } else if reply.media_type == "text/event-stream" {
                    sse_events(&reply.text)
                } else {
                    vec![Value::String(reply.text.clone())]
                };
                for body in &bodies {
                    if let Err(e) = self.v().validate(&media["schema"], body) {
                        panic!("the answer does not match its schema:\n{e}\n{what}");
                    }
                }
            }
            None => assert!(reply.text.is_empty(), "an answer without content: {what}"),
        }
        self.seen
            .borrow_mut()
            .entry((method.to_string(), template.to_string()))
            .or_default()
            .insert(reply.status);
        reply
    }

    fn revision(&self) -> u64 {
        let r = self.exchange("GET", "/healthz", "/healthz", Send::Nothing);
        r.json()["revision"].as_u64().expect("a revision")
    }

    /// A valid request: it conforms to the request schema and succeeds; a write
    /// answers the next revision.
    fn ok(&self, method: &str, template: &str, path: &str, body: Option<Value>) -> Value {
        if let (Some(b), Some(schema)) = (&body, self.request_schema(method, template))
            && let Err(e) = self.v().validate(schema, b)
        {
            panic!("{method} {path}: the contract refuses a valid request {b}:\n{e}");
        }
        let write = method != "GET" && !template.starts_with("/v1/admin") && !is_read(template);
        let before = if write { self.revision() } else { 0 };
        let send = match &body {
            Some(b) => Send::Json(b),
            None => Send::Nothing,
        };
        let r = self.exchange(method, template, path, send);
        assert!(
            (200..300).contains(&r.status),
            "{method} {path} {}: {}",
            body.map(|b| b.to_string()).unwrap_or_default(),
            r.text
        );
        let v = r.json();
        if write {
            let answered = v["revision"].as_u64().expect("a write answers a revision");
            assert_eq!(
                answered,
                self.revision(),
                "{method} {path}: a write answers the revision after it: {v}"
            );
            // One write, one revision. PATCH is the exception for now: it advances the
            // revision once per field it changes (none for `{}`).
            if method == "PATCH" {
                assert!(answered >= before, "{method} {path}: {v}");
            } else {
                assert_eq!(
                    answered,
                    before + 1,
                    "{method} {path}: one write, one revision: {v}"
                );
            }
        }
        v
    }

    /// A refused request: the status is `status`, the answer is a problem, and the
    /// world's revision is unchanged. With [`Spec::Refuses`] the request schema must
    /// refuse the body too.
    fn refused(
        &self,
        method: &str,
        template: &str,
        path: &str,
        body: Send,
        status: u16,
        spec: Spec,
    ) -> Value {
        if let (Send::Json(b), Some(schema), Spec::Refuses) =
            (&body, self.request_schema(method, template), spec)
        {
            assert!(
                self.v().validate(schema, b).is_err(),
                "{method} {path}: the contract accepts {b}, which the server refuses"
            );
        }
        let before = self.revision();
        let r = self.exchange(method, template, path, body);
        assert_eq!(r.status, status, "{method} {path}: {}", r.text);
        assert_eq!(r.media_type, "application/problem+json", "{method} {path}");
        assert_eq!(self.revision(), before, "{method} {path} changed the world");
        r.json()
    }

    /// A successful read whose answer is an image or a drawing (PNG, SVG or JSON): it
    /// conforms to the request schema, succeeds with `media` and leaves the revision.
    fn ok_drawing(
        &self,
        method: &str,
        template: &str,
        path: &str,
        body: Option<Value>,
        media: &str,
    ) -> Reply {
        if let (Some(b), Some(schema)) = (&body, self.request_schema(method, template))
            && let Err(e) = self.v().validate(schema, b)
        {
            panic!("{method} {path}: the contract refuses a valid request {b}:\n{e}");
        }
        let before = self.revision();
        let send = match &body {
            Some(b) => Send::Json(b),
            None => Send::Nothing,
        };
        let r = self.exchange(method, template, path, send);
        assert_eq!(r.status, 200, "{method} {path}: {}", r.text);
        assert_eq!(r.media_type, media, "{method} {path}");
        assert_eq!(self.revision(), before, "{method} {path} is a read");
        r
    }

    /// A successful request whose answer is text (metrics, an event stream).
    fn ok_text(&self, method: &str, template: &str, path: &str) -> String {
        let r = self.exchange(method, template, path, Send::Nothing);
        assert!(
            (200..300).contains(&r.status),
            "{method} {path}: {}",
            r.text
        );
        r.text
    }

    fn refused_json(
        &self,
        method: &str,
        template: &str,
        path: &str,
        body: Value,
        status: u16,
        spec: Spec,
    ) -> Value {
        self.refused(method, template, path, Send::Json(&body), status, spec)
    }

    fn topology(&self, id: u64) -> Value {
        let p = format!("/v1/bodies/{id}/topology");
        self.ok("GET", "/v1/bodies/{id}/topology", &p, None)
    }

    fn create(&self, req: Value) -> Value {
        let v = self.ok("POST", "/v1/bodies", "/v1/bodies", Some(req));
        assert!(v["id"].is_u64(), "{v}");
        v
    }

    fn euler(&self, body: u64, op: Value) -> Value {
        let p = format!("/v1/bodies/{body}/euler");
        self.ok("POST", "/v1/bodies/{id}/euler", &p, Some(op))
    }
}

/// Operations that use POST but only read (`/v1/camera-solution` writes only with
/// `store_as`, checked where it is tried).
fn is_read(template: &str) -> bool {
    template == "/v1/appearance"
        || template == "/v1/camera-solution"
        || template == "/v1/recognition"
        || template.starts_with("/v1/spatial/")
}

fn matches_template(template: &str, path: &str) -> bool {
    let path = path.split('?').next().unwrap_or("");
    let (t, p): (Vec<_>, Vec<_>) = (template.split('/').collect(), path.split('/').collect());
    t.len() == p.len()
        && t.iter()
            .zip(&p)
            .all(|(t, p)| t == p || (t.starts_with('{') && t.ends_with('}') && !p.is_empty()))
}

fn id(v: &Value) -> u64 {
    v.as_u64().unwrap_or_else(|| panic!("not an id: {v}"))
}

fn ids(v: &Value) -> Vec<u64> {
    v.as_array().expect("an array").iter().map(id).collect()
}

/// A face of topology `t` whose outward normal is closest to `n`.
fn face_facing(t: &Value, n: [f64; 3]) -> &Value {
    t["faces"]
        .as_array()
        .expect("faces")
        .iter()
        .max_by(|a, b| {
            let dot = |f: &Value| {
                (0..3)
                    .map(|i| f["plane"][i].as_f64().unwrap_or(0.0) * n[i])
                    .sum::<f64>()
            };
            dot(a).total_cmp(&dot(b))
        })
        .expect("a face")
}

/// The edges of face `f` in topology `t`.
fn edges_of(t: &Value, f: u64) -> Vec<u64> {
    t["edges"]
        .as_array()
        .expect("edges")
        .iter()
        .filter(|e| e["nface"] == f || e["pface"] == f)
        .map(|e| id(&e["id"]))
        .collect()
}

#[test]
fn answers_match_the_contract() {
    let world = winged::server::demo::demo_world().expect("the demo world builds");
    let server = TestServer::start(world);
    let c = Contract::new(&server.base);

    service_and_reads(&c);
    let start = c.revision();
    create_bodies(&c);
    patch_bodies(&c);
    euler_operators(&c);
    transforms(&c);
    sweeps_duals_everts_copies(&c);
    cameras(&c);
    appearance(&c);
    spatial(&c);
    camera_solution(&c);
    recognition(&c);
    perception(&c);
    lights(&c);
    deletes(&c);
    booleans(&c);
    meshes(&c);
    following(&c, start);
    unknown_route(&c);

    let seen = c.seen.borrow();
    let declared = spec_operations(&c.doc);
    let untried: Vec<_> = declared
        .iter()
        .filter(|k| {
            !seen
                .get(*k)
                .is_some_and(|s| s.iter().any(|c| (200..300).contains(c)))
        })
        .collect();
    assert!(
        untried.is_empty(),
        "operations never exercised with success: {untried:?}"
    );
    let all: BTreeSet<u16> = seen.values().flatten().copied().collect();
    for status in [200, 201, 400, 404, 409, 413, 415, 422] {
        assert!(all.contains(&status), "no exchange answered {status}");
    }
    drop(seen);
    drop(c);
    drop(server);
}

fn service_and_reads(c: &Contract) {
    let h = c.ok("GET", "/healthz", "/healthz", None);
    assert_eq!(h["status"], "ok");
    let ready = c.ok("GET", "/readyz", "/readyz", None);
    assert_eq!(ready["revision"], h["revision"]);
    c.ok("GET", "/openapi.json", "/openapi.json", None);
    let w = c.ok("GET", "/v1/world", "/v1/world", None);
    let list = c.ok("GET", "/v1/bodies", "/v1/bodies", None);
    let bodies = list["bodies"].as_array().expect("bodies");
    assert_eq!(w["bodies"].as_u64(), Some(bodies.len() as u64), "{w}");
    assert!(
        bodies.iter().all(|b| b["id"] != 1),
        "the world body is not listed"
    );

    let cube = c.ok("GET", "/v1/bodies", "/v1/bodies?name=cube", None);
    assert_eq!(cube["bodies"].as_array().map(Vec::len), Some(1), "{cube}");
    let table = id(&c.ok("GET", "/v1/bodies", "/v1/bodies?name=table", None)["bodies"][0]["id"]);
    let parts = c.ok(
        "GET",
        "/v1/bodies",
        &format!("/v1/bodies?parent={table}"),
        None,
    );
    assert!(!parts["bodies"].as_array().expect("bodies").is_empty());
    c.refused(
        "GET",
        "/v1/bodies",
        "/v1/bodies?colour=red",
        Send::Nothing,
        400,
        Spec::Either,
    );
    c.refused(
        "GET",
        "/v1/bodies",
        "/v1/bodies?parent=x",
        Send::Nothing,
        400,
        Spec::Either,
    );

    let t = c.ok(
        "GET",
        "/v1/bodies/{id}",
        &format!("/v1/bodies/{table}"),
        None,
    );
    assert_eq!(t["name"], "table");
    let root = c.ok("GET", "/v1/bodies/{id}", "/v1/bodies/1", None);
    assert!(root["bounds"].is_null(), "{root}");
    c.refused(
        "GET",
        "/v1/bodies/{id}",
        "/v1/bodies/abc",
        Send::Nothing,
        400,
        Spec::Either,
    );
    c.refused(
        "GET",
        "/v1/bodies/{id}",
        "/v1/bodies/999999",
        Send::Nothing,
        404,
        Spec::Either,
    );

    let topo = c.topology(table);
    assert_eq!(topo["faces"].as_array().map(Vec::len), Some(6));
    c.topology(1);
    let tp = "/v1/bodies/{id}/topology";
    c.refused(
        "GET",
        tp,
        "/v1/bodies/999999/topology",
        Send::Nothing,
        404,
        Spec::Either,
    );
    c.refused(
        "GET",
        tp,
        "/v1/bodies/x/topology",
        Send::Nothing,
        400,
        Spec::Either,
    );
}

fn create_bodies(c: &Contract) {
    let square = json!([[0, 0], [1, 0], [1, 1], [0, 1]]);
    let shapes = [
        json!({"type": "box", "size": [1, 2, 3]}),
        json!({"type": "tetrahedron", "radius": 1}),
        json!({"type": "prism", "polygon": square, "height": 1}),
        json!({"type": "pyramid", "polygon": square, "height": 0.5}),
        json!({"type": "cylinder", "radius": 1, "height": 2}),
        json!({"type": "cylinder", "radius": 1, "height": 2, "segments": 6}),
        json!({"type": "cone", "radius": 1, "height": 1, "segments": 5}),
        json!({"type": "sphere", "radius": 1, "segments": 6, "rings": 3}),
        json!({"type": "torus", "major_radius": 2, "minor_radius": 0.5, "segments": 6, "rings": 4}),
        json!({"type": "polyhedron",
               "vertices": [[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]],
               "faces": [[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]]}),
    ];
    for shape in shapes {
        let made = c.create(json!({ "shape": shape }));
        assert!(made.get("face").is_none(), "{made}");
    }
    let table = id(&c.ok("GET", "/v1/bodies", "/v1/bodies?name=table", None)["bodies"][0]["id"]);
    let block = c.create(json!({
        "name": "block",
        "parent": table,
        "pose": {"position": [0, 0, 0.5], "rotation": [0, 0, 0, 1]},
        "shape": {"type": "box", "size": [0.2, 0.2, 0.2]}
    }));
    let b = c.ok(
        "GET",
        "/v1/bodies/{id}",
        &format!("/v1/bodies/{}", id(&block["id"])),
        None,
    );
    assert_eq!(b["parent"].as_u64(), Some(table));

    let seed = c.create(json!({"shape": {"type": "seminal", "position": [1, 2, 3]}}));
    assert_eq!(
        (seed["faces"].as_u64(), seed["vertices"].as_u64()),
        (Some(1), Some(1))
    );
    let t = c.topology(id(&seed["id"]));
    assert!(
        t["vertices"][0]["ped"].is_null() && t["faces"][0]["plane"].is_null(),
        "{t}"
    );
    assert_eq!(t["faces"][0]["id"], seed["face"]);

    let post = |body: Value, status: u16, spec: Spec| {
        c.refused_json("POST", "/v1/bodies", "/v1/bodies", body, status, spec)
    };
    post(json!({"shape": {"type": "blob"}}), 400, Spec::Refuses);
    post(json!({"name": "x"}), 400, Spec::Refuses);
    post(
        json!({"shape": {"type": "box", "size": [1, 1, 1]}, "colour": "red"}),
        400,
        Spec::Refuses,
    );
    post(
        json!({"shape": {"type": "box", "size": [1, 1]}}),
        400,
        Spec::Refuses,
    );
    post(json!({"shape": {"type": "box"}}), 400, Spec::Refuses);
    post(
        json!({"shape": {"type": "seminal"}, "parent": 1.5}),
        400,
        Spec::Refuses,
    );
    post(
        json!({"name": " padded", "shape": {"type": "seminal"}}),
        422,
        Spec::Refuses,
    );
    post(
        json!({"shape": {"type": "seminal"}, "pose": {"rotation": [0, 0, 0, 0]}}),
        422,
        Spec::Either,
    );
    post(
        json!({"name": "block", "shape": {"type": "seminal"}}),
        409,
        Spec::Either,
    );
    post(
        json!({"shape": {"type": "box", "size": [-1, 1, 1]}}),
        422,
        Spec::Refuses,
    );
    post(
        json!({"shape": {"type": "torus", "major_radius": 1, "minor_radius": 2}}),
        422,
        Spec::Either,
    );
    post(
        json!({"shape": {"type": "polyhedron", "vertices": [[0, 0, 0]], "faces": [[0, 0, 0]]}}),
        422,
        Spec::Either,
    );
    post(
        json!({"parent": 999999, "shape": {"type": "seminal"}}),
        404,
        Spec::Either,
    );
    post(
        json!({"shape": {"type": "sphere", "radius": 1, "segments": 100000, "rings": 100000}}),
        413,
        Spec::Either,
    );
    let raw = |ct: Option<&str>, bytes: &[u8], status: u16| {
        c.refused(
            "POST",
            "/v1/bodies",
            "/v1/bodies",
            Send::Raw(ct, bytes),
            status,
            Spec::Either,
        )
    };
    raw(Some("application/json"), b"{bad", 400);
    raw(Some("application/json"), b"", 400);
    raw(Some("text/plain"), br#"{"shape":{"type":"seminal"}}"#, 415);
    raw(None, br#"{"shape":{"type":"seminal"}}"#, 415);
}

fn body_named(c: &Contract, name: &str) -> u64 {
    let l = c.ok(
        "GET",
        "/v1/bodies",
        &format!("/v1/bodies?name={name}"),
        None,
    );
    id(&l["bodies"][0]["id"])
}

fn patch_bodies(c: &Contract) {
    let block = body_named(c, "block");
    let p = format!("/v1/bodies/{block}");
    let t = "/v1/bodies/{id}";
    let changed = c.ok("PATCH", t, &p, Some(json!({"name": "brick"})));
    assert_eq!(changed["id"].as_u64(), Some(block));
    c.ok("PATCH", t, &p, Some(json!({"name": null})));
    assert!(c.ok("GET", t, &p, None)["name"].is_null());
    c.ok(
        "PATCH",
        t,
        &p,
        Some(json!({"name": "block", "pose": {"position": [0, 0, 1]}})),
    );
    let before = c.ok("GET", t, &p, None);
    assert_eq!(before["pose"]["position"], json!([0.0, 0.0, 1.0]));
    c.ok("PATCH", t, &p, Some(json!({"parent": 1})));
    c.ok("PATCH", t, &p, Some(json!({})));
    let after = c.ok("GET", t, &p, None);
    assert_eq!(after["parent"], 1);
    // Re-parenting does not move the body.
    assert_eq!(after["pose"], before["world_pose"], "{before}\n{after}");

    c.refused_json("PATCH", t, &p, json!({"name": "table"}), 409, Spec::Either);
    c.refused_json("PATCH", t, &p, json!({"parent": block}), 422, Spec::Either);
    c.refused_json(
        "PATCH",
        t,
        "/v1/bodies/1",
        json!({"name": "x"}),
        422,
        Spec::Either,
    );
    c.refused_json("PATCH", t, &p, json!({"name": ""}), 422, Spec::Refuses);
    c.refused_json("PATCH", t, &p, json!({"colour": 1}), 400, Spec::Refuses);
    c.refused_json(
        "PATCH",
        t,
        &p,
        json!({"pose": {"position": [0, 0]}}),
        400,
        Spec::Refuses,
    );
    c.refused_json(
        "PATCH",
        t,
        "/v1/bodies/999999",
        json!({"name": "x"}),
        404,
        Spec::Either,
    );
    c.refused_json("PATCH", t, &p, json!({"parent": 999999}), 404, Spec::Either);
    c.refused(
        "PATCH",
        t,
        &p,
        Send::Raw(Some("text/plain"), b"{}"),
        415,
        Spec::Either,
    );
}

fn euler_operators(c: &Contract) {
    let eu = "/v1/bodies/{id}/euler";
    // ESPLIT and KLEV, MKFE and KLFE, INVERT, KLVE on a box.
    let b = id(&c.create(json!({"shape": {"type": "box", "size": [2, 2, 2]}}))["id"]);
    let t = c.topology(b);
    let f0 = &t["faces"][0];
    let (f, fv) = (id(&f0["id"]), ids(&f0["vertices"]));
    let e0 = edges_of(&t, f)[0];
    let split = c.euler(b, json!({"op": "esplit", "edge": e0}));
    assert_eq!(
        (split["edges"].as_u64(), split["vertices"].as_u64()),
        (Some(13), Some(9))
    );
    let back = c.euler(b, json!({"op": "klev", "vertex": split["vertex"]}));
    assert_eq!(back["edges"].as_u64(), Some(12), "{back}");
    let cut = c.euler(
        b,
        json!({"op": "mkfe", "v1": fv[0], "face": f, "v2": fv[2]}),
    );
    assert_eq!(cut["faces"].as_u64(), Some(7), "{cut}");
    assert!(cut["face"].is_u64() && cut["edge"].is_u64(), "{cut}");
    let merged = c.euler(b, json!({"op": "klfe", "edge": cut["edge"]}));
    assert_eq!(merged["faces"].as_u64(), Some(6), "{merged}");
    let turned = c.euler(b, json!({"op": "invert", "edge": e0}));
    assert_eq!(turned["edge"].as_u64(), Some(e0));
    let split = c.euler(
        b,
        json!({"op": "esplit", "edge": e0, "position": [1, 1, 1]}),
    );
    let contracted = c.euler(b, json!({"op": "klve", "edge": split["edge"]}));
    assert!(contracted["vertex"].is_u64(), "{contracted}");

    // MKEV from a seminal body.
    let s = c.create(json!({"shape": {"type": "seminal"}}));
    let spur = c.euler(
        id(&s["id"]),
        json!({"op": "mkev", "face": s["face"], "vertex": s["vertex"], "position": [1, 0, 0]}),
    );
    assert_eq!(
        (spur["edges"].as_u64(), spur["vertices"].as_u64()),
        (Some(1), Some(2))
    );

    // GLUE two unit boxes face to face: the second body is merged into the first.
    let unit = |x: f64| {
        id(
            &c.create(json!({"shape": {"type": "box", "size": [1, 1, 1]},
                             "pose": {"position": [x, 0, 0]}}))["id"],
        )
    };
    let (p, q) = (unit(0.0), unit(1.0));
    let (fp, fq) = (
        face_facing(&c.topology(p), [1.0, 0.0, 0.0])["id"].clone(),
        face_facing(&c.topology(q), [-1.0, 0.0, 0.0])["id"].clone(),
    );
    let glued = c.euler(p, json!({"op": "glue", "face1": fp, "face2": fq}));
    assert_eq!(glued["faces"].as_u64(), Some(10), "{glued}");
    c.refused(
        "GET",
        "/v1/bodies/{id}",
        &format!("/v1/bodies/{q}"),
        Send::Nothing,
        404,
        Spec::Either,
    );

    // GLUEFF: a tube between two boxes apart.
    let (p, q) = (unit(0.0), unit(3.0));
    let (fp, fq) = (
        face_facing(&c.topology(p), [1.0, 0.0, 0.0])["id"].clone(),
        face_facing(&c.topology(q), [-1.0, 0.0, 0.0])["id"].clone(),
    );
    let tube = c.euler(p, json!({"op": "glueff", "face1": fp, "face2": fq}));
    assert_eq!(
        tube["new_edges"].as_array().map(Vec::len),
        Some(4),
        "{tube}"
    );

    // GLUEE: a wasp edge between two boxes apart.
    let (p, q) = (unit(0.0), unit(3.0));
    let (tp, tq) = (c.topology(p), c.topology(q));
    let (gp, gq) = (
        face_facing(&tp, [1.0, 0.0, 0.0]),
        face_facing(&tq, [-1.0, 0.0, 0.0]),
    );
    let wasp = c.euler(
        p,
        json!({"op": "gluee", "face1": gp["id"], "vertex1": gp["vertices"][0],
               "face2": gq["id"], "vertex2": gq["vertices"][0]}),
    );
    assert!(wasp["edge"].is_u64(), "{wasp}");

    // UNGLUE round one face: the face comes off as a body of its own.
    let u = unit(5.0);
    let t = c.topology(u);
    let top = id(&face_facing(&t, [0.0, 0.0, 1.0])["id"]);
    let cut = c.euler(u, json!({"op": "unglue", "edges": edges_of(&t, top)}));
    assert!(
        cut["split_off"].is_u64() && cut["new_face"].is_u64(),
        "{cut}"
    );

    // Refusals, on a fresh box whose corners all have three edges.
    let r = unit(8.0);
    let path = format!("/v1/bodies/{r}/euler");
    let corner = id(&c.topology(r)["vertices"][0]["id"]);
    let no = |body: Value, status: u16, spec: Spec| {
        c.refused_json("POST", eu, &path, body, status, spec)
    };
    let refused = no(json!({"op": "klev", "vertex": corner}), 422, Spec::Either);
    assert_eq!(refused["type"], "urn:winged:problem:euler-refused");
    no(json!({"op": "unglue", "edges": []}), 422, Spec::Either);
    no(json!({"op": "twist", "edge": 1}), 400, Spec::Refuses);
    no(json!({"op": "klfe"}), 400, Spec::Refuses);
    no(
        json!({"op": "klfe", "edge": 1, "face": 2}),
        400,
        Spec::Refuses,
    );
    no(json!({"op": "klfe", "edge": -1}), 400, Spec::Refuses);
    no(json!({"op": "klfe", "edge": e0}), 404, Spec::Either);
    c.refused_json(
        "POST",
        eu,
        "/v1/bodies/999999/euler",
        json!({"op": "klfe", "edge": 1}),
        404,
        Spec::Either,
    );
    c.refused(
        "POST",
        eu,
        &path,
        Send::Raw(Some("text/plain"), b"{}"),
        415,
        Spec::Either,
    );
}

fn transforms(c: &Contract) {
    let tr = "/v1/bodies/{id}/transform";
    let b = id(&c.create(json!({"shape": {"type": "box", "size": [1, 1, 1]}}))["id"]);
    let p = format!("/v1/bodies/{b}/transform");
    let top = id(&face_facing(&c.topology(b), [0.0, 0.0, 1.0])["id"]);
    c.ok(
        "POST",
        tr,
        &p,
        Some(json!({"op": "translate", "vector": [1, 0, 0]})),
    );
    // A translation of the body itself changes its pose.
    let moved = c.ok("GET", "/v1/bodies/{id}", &format!("/v1/bodies/{b}"), None);
    assert_eq!(
        moved["world_pose"]["position"],
        json!([1.0, 0.0, 0.0]),
        "{moved}"
    );
    for req in [
        json!({"op": "rotate", "axis": [0, 0, 1], "angle_deg": 30, "center": [1, 0, 0], "frame": "body"}),
        json!({"op": "dilate", "factor": 2, "center": [0, 0, 0], "frame": "world"}),
        json!({"op": "reflect", "normal": [1, 0, 0], "point": [0.5, 0, 0]}),
        json!({"op": "translate", "vector": [0, 0, 0.25], "target": top}),
    ] {
        let v = c.ok("POST", tr, &p, Some(req));
        assert_eq!(v["id"].as_u64(), Some(b), "{v}");
    }
    let no =
        |body: Value, status: u16, spec: Spec| c.refused_json("POST", tr, &p, body, status, spec);
    let bad = no(json!({"op": "dilate", "factor": 0}), 422, Spec::Refuses);
    assert_eq!(bad["type"], "urn:winged:problem:invalid-transform");
    no(
        json!({"op": "shear", "vector": [1, 0, 0]}),
        400,
        Spec::Refuses,
    );
    no(json!({"op": "translate"}), 400, Spec::Refuses);
    no(
        json!({"op": "translate", "vector": [1, 0, 0], "frame": "camera"}),
        400,
        Spec::Refuses,
    );
    no(
        json!({"op": "translate", "vector": [1, 0, 0], "target": 1}),
        404,
        Spec::Either,
    );
    c.refused_json(
        "POST",
        tr,
        "/v1/bodies/999999/transform",
        json!({"op": "translate", "vector": [1, 0, 0]}),
        404,
        Spec::Either,
    );
    c.refused(
        "POST",
        tr,
        &p,
        Send::Raw(Some("text/plain"), b"{}"),
        415,
        Spec::Either,
    );
}

fn sweeps_duals_everts_copies(c: &Contract) {
    let square = json!([[0, 0], [1, 0], [1, 1], [0, 1]]);
    let b =
        id(&c.create(json!({"shape": {"type": "prism", "polygon": square, "height": 1}}))["id"]);
    let top = id(&face_facing(&c.topology(b), [0.0, 0.0, 1.0])["id"]);
    let sw = "/v1/bodies/{id}/sweep";
    let p = format!("/v1/bodies/{b}/sweep");
    let s = c.ok(
        "POST",
        sw,
        &p,
        Some(json!({"face": top, "kind": "prism", "distance": 0.5})),
    );
    assert_eq!(
        (s["face"].as_u64(), s["faces"].as_u64()),
        (Some(top), Some(10)),
        "{s}"
    );
    c.ok(
        "POST",
        sw,
        &p,
        Some(json!({"face": top, "kind": "cw_prismoid", "distance": 0.2, "scale": 0.5})),
    );
    c.ok(
        "POST",
        sw,
        &p,
        Some(json!({"face": top, "kind": "ccw_prismoid", "offset": [0, 0, 0.1]})),
    );
    c.ok(
        "POST",
        sw,
        &p,
        Some(json!({"face": top, "kind": "pyramid", "peak": [0.5, 0.5, 3]})),
    );
    let no =
        |body: Value, status: u16, spec: Spec| c.refused_json("POST", sw, &p, body, status, spec);
    no(json!({"face": top, "kind": "twist"}), 400, Spec::Refuses);
    no(json!({"kind": "prism"}), 400, Spec::Refuses);
    no(
        json!({"face": top, "kind": "prism", "height": 1}),
        400,
        Spec::Refuses,
    );
    no(json!({"face": 1, "kind": "prism"}), 404, Spec::Either);
    c.refused("POST", sw, &p, Send::Raw(None, b"{}"), 415, Spec::Either);

    let cube = id(&c.create(json!({"shape": {"type": "box", "size": [1, 1, 1]}}))["id"]);
    let du = "/v1/bodies/{id}/dual";
    let d = c.ok("POST", du, &format!("/v1/bodies/{cube}/dual"), None);
    assert_eq!(
        (d["faces"].as_u64(), d["vertices"].as_u64()),
        (Some(8), Some(6)),
        "{d}"
    );
    c.refused(
        "POST",
        du,
        "/v1/bodies/1/dual",
        Send::Nothing,
        422,
        Spec::Either,
    );
    c.refused(
        "POST",
        du,
        "/v1/bodies/999999/dual",
        Send::Nothing,
        404,
        Spec::Either,
    );
    c.refused(
        "POST",
        du,
        "/v1/bodies/x/dual",
        Send::Nothing,
        400,
        Spec::Either,
    );

    let ev = "/v1/bodies/{id}/evert";
    let e = c.ok("POST", ev, &format!("/v1/bodies/{cube}/evert"), None);
    assert_eq!(e["id"].as_u64(), Some(cube));
    c.ok("POST", ev, &format!("/v1/bodies/{cube}/evert"), None);
    c.refused(
        "POST",
        ev,
        "/v1/bodies/1/evert",
        Send::Nothing,
        422,
        Spec::Either,
    );
    c.refused(
        "POST",
        ev,
        "/v1/bodies/999999/evert",
        Send::Nothing,
        404,
        Spec::Either,
    );

    let cp = "/v1/bodies/{id}/copy";
    let p = format!("/v1/bodies/{cube}/copy");
    let copy = c.ok("POST", cp, &p, None);
    assert_ne!(copy["id"].as_u64(), Some(cube));
    assert_eq!(copy["faces"].as_u64(), Some(8), "{copy}");
    c.ok("POST", cp, &p, Some(json!({})));
    c.ok("POST", cp, &p, Some(json!({"name": "copy1"})));
    c.refused_json("POST", cp, &p, json!({"name": "copy1"}), 409, Spec::Either);
    c.refused_json("POST", cp, &p, json!({"nme": "x"}), 400, Spec::Refuses);
    c.refused(
        "POST",
        cp,
        &p,
        Send::Raw(Some("application/json"), b"{bad"),
        400,
        Spec::Either,
    );
    c.refused(
        "POST",
        cp,
        &p,
        Send::Raw(Some("text/plain"), b"{}"),
        415,
        Spec::Either,
    );
    c.refused(
        "POST",
        cp,
        "/v1/bodies/999999/copy",
        Send::Nothing,
        404,
        Spec::Either,
    );
}

fn booleans(c: &Contract) {
    let t = "/v1/bodies/{id}/boolean";
    let a = id(&c.create(json!({"shape": {"type": "box", "size": [2, 2, 2]}}))["id"]);
    let b = id(&c.create(json!({
        "shape": {"type": "box", "size": [2, 2, 2]},
        "pose": {"position": [1, 0, 0]}
    }))["id"]);
    let part =
        id(&c.create(json!({"shape": {"type": "box", "size": [1, 1, 1]}, "parent": a}))["id"]);
    let p = format!("/v1/bodies/{a}/boolean");
    let no = |path: &str, body: Value, status: u16, spec: Spec| {
        c.refused_json("POST", t, path, body, status, spec)
    };
    no(&p, json!({"op": "xor", "with": b}), 400, Spec::Refuses);
    no(&p, json!({"op": "union"}), 400, Spec::Refuses);
    no(
        &p,
        json!({"op": "union", "with": b, "keep": true}),
        400,
        Spec::Refuses,
    );
    no(
        &p,
        json!({"op": "union", "with": 999_999}),
        404,
        Spec::Either,
    );
    no(
        "/v1/bodies/999999/boolean",
        json!({"op": "union", "with": b}),
        404,
        Spec::Either,
    );
    let itself = no(&p, json!({"op": "union", "with": a}), 422, Spec::Either);
    assert_eq!(itself["type"], "urn:winged:problem:boolean-refused");
    no(
        &p,
        json!({"op": "difference", "with": part}),
        422,
        Spec::Either,
    );
    no(&p, json!({"op": "union", "with": 1}), 422, Spec::Either);
    c.refused(
        "POST",
        t,
        &p,
        Send::Raw(Some("text/plain"), b"{}"),
        415,
        Spec::Either,
    );
    // Two overlapping boxes, kept: one piece of 12 m³.
    let u = c.ok(
        "POST",
        t,
        &p,
        Some(json!({"op": "union", "with": b, "keep_with": true})),
    );
    assert_eq!(u["id"].as_u64(), Some(a), "{u}");
    assert_eq!(u["pieces"].as_array().map(Vec::len), Some(1), "{u}");
    assert_eq!(ids(&u["killed"]), Vec::<u64>::new(), "{u}");
}

fn cameras(c: &Contract) {
    let (one, list) = ("/v1/cameras/{name}", "/v1/cameras");
    let cams = c.ok("GET", list, list, None);
    assert_eq!(cams["cameras"][0]["name"], "eye", "{cams}");
    let eye = c.ok("GET", one, "/v1/cameras/eye", None);
    assert_eq!(eye["name"], "eye");
    let intrinsics = json!({"width": 64, "height": 48, "fx": 60, "fy": 60, "cx": 32, "cy": 24});
    c.ok(
        "PUT",
        one,
        "/v1/cameras/front",
        Some(json!({
            "look_at": {"eye": [3, 0, 1], "target": [0, 0, 0]},
            "intrinsics": intrinsics
        })),
    );
    let front = c.ok("GET", one, "/v1/cameras/front", None);
    let d = front["view_direction"].as_array().expect("a direction");
    assert!(d[0].as_f64().expect("x") < -0.9, "looks toward −x: {front}");
    c.ok(
        "PUT",
        one,
        "/v1/cameras/top",
        Some(json!({
            "pose": {"position": [0, 0, 5]},
            "baumgart": {"focal": 35, "ldx": 640, "ldy": 480, "pdx": 36, "pdy": 24}
        })),
    );
    let top = c.ok("GET", one, "/v1/cameras/top", None);
    assert_eq!(
        top["view_direction"][2].as_f64(),
        Some(-1.0),
        "looks along −k: {top}"
    );
    assert_eq!(top["intrinsics"]["fy"].as_f64(), Some(700.0), "{top}");
    // Replacing a camera is a write too.
    c.ok(
        "PUT",
        one,
        "/v1/cameras/top",
        Some(json!({"pose": {}, "intrinsics": intrinsics})),
    );
    let cams = c.ok("GET", list, list, None);
    assert_eq!(cams["cameras"].as_array().map(Vec::len), Some(3), "{cams}");

    let p = "/v1/cameras/side";
    let no =
        |body: Value, status: u16, spec: Spec| c.refused_json("PUT", one, p, body, status, spec);
    let lensless = no(json!({"pose": {}}), 422, Spec::Refuses);
    assert_eq!(lensless["type"], "urn:winged:problem:invalid-camera");
    no(
        json!({"pose": {}, "look_at": {"eye": [1, 0, 0], "target": [0, 0, 0]}, "intrinsics": intrinsics}),
        422,
        Spec::Refuses,
    );
    no(
        json!({"pose": {}, "intrinsics": {"width": 0, "height": 48, "fx": 60, "fy": 60, "cx": 32, "cy": 24}}),
        422,
        Spec::Refuses,
    );
    no(
        json!({"look_at": {"eye": [1, 1, 1], "target": [1, 1, 1]}, "intrinsics": intrinsics}),
        422,
        Spec::Either,
    );
    no(
        json!({"pose": {}, "intrinsics": intrinsics, "lens": 1}),
        400,
        Spec::Refuses,
    );
    no(
        json!({"pose": {}, "intrinsics": {"width": 64}}),
        400,
        Spec::Refuses,
    );
    c.refused_json(
        "PUT",
        one,
        "/v1/cameras/%20side",
        json!({"pose": {}, "intrinsics": intrinsics}),
        422,
        Spec::Either,
    );
    c.refused(
        "PUT",
        one,
        p,
        Send::Raw(Some("text/plain"), b"{}"),
        415,
        Spec::Either,
    );
    c.refused(
        "GET",
        one,
        "/v1/cameras/nowhere",
        Send::Nothing,
        404,
        Spec::Either,
    );

    c.ok("DELETE", one, "/v1/cameras/top", None);
    c.refused(
        "DELETE",
        one,
        "/v1/cameras/top",
        Send::Nothing,
        404,
        Spec::Either,
    );
    c.refused(
        "GET",
        one,
        "/v1/cameras/top",
        Send::Nothing,
        404,
        Spec::Either,
    );
}

fn appearance(c: &Contract) {
    let (image, post) = ("/v1/cameras/{name}/image", "/v1/appearance");
    let png = c.ok_drawing("GET", image, "/v1/cameras/eye/image", None, "image/png");
    assert!(png.text.starts_with("\u{FFFD}PNG"), "a PNG signature");
    for mode in ["wire", "hidden", "depth", "ids"] {
        let path = format!("/v1/cameras/eye/image?mode={mode}&width=160");
        c.ok_drawing("GET", image, &path, None, "image/png");
    }
    let lines = c.ok_drawing(
        "GET",
        image,
        "/v1/cameras/eye/image?mode=hidden&format=json",
        None,
        "application/json",
    );
    assert!(
        !lines.json()["segments"]
            .as_array()
            .expect("segments")
            .is_empty()
    );
    let ids = c.ok_drawing(
        "GET",
        image,
        "/v1/cameras/eye/image?mode=ids&format=json",
        None,
        "application/json",
    );
    assert!(ids.json()["bodies"].as_array().expect("bodies").len() >= 5);
    c.ok_drawing(
        "GET",
        image,
        "/v1/cameras/eye/image?mode=hidden&format=svg",
        None,
        "image/svg+xml",
    );
    c.ok_drawing(
        "POST",
        post,
        post,
        Some(json!({"camera": "eye", "mode": "depth", "depth_scale": 0.0005})),
        "image/png",
    );
    let inline = json!({
        "camera": {
            "look_at": {"eye": [2, -2, 2], "target": [0, 0, 0.75]},
            "intrinsics": {"width": 64, "height": 48, "fx": 60, "fy": 60, "cx": 32, "cy": 24}
        },
        "mode": "hidden",
        "format": "json"
    });
    c.ok_drawing("POST", post, post, Some(inline), "application/json");

    let nobody = "/v1/cameras/nobody/image";
    c.refused("GET", image, nobody, Send::Nothing, 404, Spec::Either);
    let bogus = "/v1/cameras/eye/image?mode=bogus";
    c.refused("GET", image, bogus, Send::Nothing, 400, Spec::Either);
    let huge = "/v1/cameras/eye/image?width=16000&height=16000";
    c.refused("GET", image, huge, Send::Nothing, 422, Spec::Either);
    c.refused_json(
        "POST",
        post,
        post,
        json!({"camera": "eye", "mode": "sketch"}),
        400,
        Spec::Refuses,
    );
    c.refused_json(
        "POST",
        post,
        post,
        json!({"camera": "nobody"}),
        404,
        Spec::Either,
    );
    c.refused_json(
        "POST",
        post,
        post,
        json!({"camera": {"look_at": {"eye": [1, 1, 1], "target": [1, 1, 1]},
                          "intrinsics": {"width": 8, "height": 8, "fx": 8, "fy": 8,
                                         "cx": 4, "cy": 4}}}),
        422,
        Spec::Either,
    );
}

/// A grey PNG of `pixels` (row-major), in base64.
fn meshes(c: &Contract) {
    use base64::Engine as _;
    let off = "OFF\n4 4 6\n0 0 0\n1 0 0\n0 1 0\n0 0 1\n3 0 2 1\n3 0 1 3\n3 0 3 2\n3 1 2 3\n";
    let made = c.ok(
        "POST",
        "/v1/bodies",
        "/v1/bodies",
        Some(
            json!({"name": "wedge-mesh", "shape": {"type": "mesh", "format": "off",
            "data": base64::engine::general_purpose::STANDARD.encode(off),
            "merge_coplanar": true}}),
        ),
    );
    assert_eq!(made["bodies"].as_array().map(Vec::len), Some(1), "{made}");
    let id = made["id"].as_u64().expect("an id");
    let (one, import) = ("/v1/bodies/{id}/mesh", "/v1/bodies/import");
    for (format, media) in [
        ("obj", "model/obj"),
        ("stl", "model/stl"),
        ("ply", "application/x-ply"),
        ("off", "application/x-off"),
        ("glb", "model/gltf-binary"),
        ("3mf", "model/3mf"),
    ] {
        let path = format!("/v1/bodies/{id}/mesh?format={format}&frame=body");
        let file = c.ok_drawing("GET", one, &path, None, media);
        let before = c.revision();
        let back = c.exchange(
            "POST",
            import,
            &format!("/v1/bodies/import?format={format}&name=wedge-{format}"),
            Send::Raw(Some("application/octet-stream"), &file.bytes),
        );
        assert_eq!(back.status, 201, "{format}: {}", back.text);
        assert_eq!(back.json()["revision"].as_u64(), Some(before + 1));
    }
    c.ok_drawing(
        "GET",
        "/v1/world/mesh",
        "/v1/world/mesh",
        None,
        "model/gltf-binary",
    );
    let open = b"OFF\n4 3 0\n0 0 0\n1 0 0\n0 1 0\n0 0 1\n3 0 2 1\n3 0 1 3\n3 0 3 2\n";
    let p = c.refused(
        "POST",
        import,
        "/v1/bodies/import?format=off",
        Send::Raw(Some("application/octet-stream"), open),
        422,
        Spec::Either,
    );
    assert_eq!(p["type"], "urn:winged:problem:mesh-invalid");
    c.refused(
        "POST",
        import,
        "/v1/bodies/import?format=stl",
        Send::Raw(Some("application/octet-stream"), b"solid x\nfacet"),
        422,
        Spec::Either,
    );
    c.refused(
        "POST",
        import,
        "/v1/bodies/import?format=blend",
        Send::Raw(Some("application/octet-stream"), b"BLENDER"),
        400,
        Spec::Either,
    );
    c.refused(
        "GET",
        one,
        "/v1/bodies/999999/mesh",
        Send::Nothing,
        404,
        Spec::Either,
    );
    c.refused(
        "GET",
        "/v1/world/mesh",
        "/v1/world/mesh?format=obj",
        Send::Nothing,
        400,
        Spec::Either,
    );
}

fn grey_png(width: u32, height: u32, pixels: &[u8]) -> String {
    use base64::Engine as _;
    let mut png = Vec::new();
    let mut encoder = png::Encoder::new(&mut png, width, height);
    encoder.set_color(png::ColorType::Grayscale);
    encoder
        .write_header()
        .expect("a header")
        .write_image_data(pixels)
        .expect("pixels");
    base64::engine::general_purpose::STANDARD.encode(png)
}

fn recognition(c: &Contract) {
    let path = "/v1/recognition";
    let eye = c.ok("GET", "/v1/cameras/{name}", "/v1/cameras/eye", None);
    let size = |k: &str| eye["intrinsics"][k].as_u64().expect("a size") as u32;
    let grey =
        |width: u32, height: u32| grey_png(width, height, &vec![90u8; (width * height) as usize]);
    let before = c.revision();
    // A blank picture: whatever the model has in view is absent.
    let got = c.ok(
        "POST",
        path,
        path,
        Some(
            json!({"camera": "eye", "image": grey(size("width"), size("height")),
                    "unexplained_mask": true}),
        ),
    );
    assert_eq!(got["revision"], before, "{got}");
    assert!(
        got["bodies"]
            .as_array()
            .expect("bodies")
            .iter()
            .all(|b| b["status"] == "absent"),
        "{got}"
    );
    assert_eq!(c.revision(), before, "recognition reads only");
    c.refused_json(
        "POST",
        path,
        path,
        json!({"camera": "eye", "image": grey(8, 8)}),
        422,
        Spec::Either,
    );
    c.refused_json(
        "POST",
        path,
        path,
        json!({"camera": "eye", "image": "not base64!"}),
        400,
        Spec::Either,
    );
    c.refused_json(
        "POST",
        path,
        path,
        json!({"camera": "nobody", "image": grey(8, 8)}),
        404,
        Spec::Either,
    );
    let p = c.refused_json(
        "POST",
        path,
        path,
        json!({"camera": "eye", "image": grey(size("width"), size("height")),
               "depth_scale": 0.0}),
        422,
        Spec::Either,
    );
    assert_eq!(p["type"], "urn:winged:problem:invalid-depth", "{p}");
}

fn perception(c: &Contract) {
    let path = "/v1/perception";
    let eye = c.ok("GET", "/v1/cameras/{name}", "/v1/cameras/eye", None);
    let size = |k: &str| eye["intrinsics"][k].as_u64().expect("a size") as u32;
    let (w, h) = (size("width"), size("height"));
    // A mask: a rectangle in the middle of the picture (or nothing).
    let mask = |width: u32, height: u32, filled: bool| {
        let pixels: Vec<u8> = (0..height)
            .flat_map(|y| {
                (0..width).map(move |x| {
                    let inside = x > width * 2 / 5
                        && x < width * 3 / 5
                        && y > height / 3
                        && y < height * 2 / 3;
                    if filled && inside { 255 } else { 0 }
                })
            })
            .collect();
        grey_png(width, height, &pixels)
    };
    let view = json!({"camera": "eye", "mask": mask(w, h, true)});
    let made = c.ok(
        "POST",
        path,
        path,
        Some(json!({"views": [view.clone()], "name": "seen-there", "far": 3.0})),
    );
    let id = made["inserted"][0]["id"].as_u64().expect("a new body");
    let body = c.ok("GET", "/v1/bodies/{id}", &format!("/v1/bodies/{id}"), None);
    assert_eq!(body["provisional"], true, "{body}");
    assert_eq!(body["views"], 1, "{body}");
    let carved = c.ok(
        "POST",
        path,
        path,
        Some(json!({"views": [view], "body": id, "far": 3.0})),
    );
    assert_eq!(carved["carved"][0]["id"], id, "{carved}");
    assert_eq!(carved["carved"][0]["views"], 2, "{carved}");
    let before = c.revision();
    for (refused, status) in [
        (
            json!({"views": [{"camera": "eye", "mask": mask(8, 8, true)}]}),
            422,
        ),
        (
            json!({"views": [{"camera": "eye", "mask": mask(w, h, false)}]}),
            422,
        ),
        (json!({"views": [{"camera": "eye"}]}), 400),
        (
            json!({"views": [{"camera": "nobody", "mask": mask(8, 8, true)}]}),
            404,
        ),
        (
            json!({"views": [{"camera": "eye", "mask": "not base64!"}]}),
            400,
        ),
        (json!({"views": []}), 422),
    ] {
        c.refused_json("POST", path, path, refused, status, Spec::Either);
    }
    assert_eq!(c.revision(), before, "refusals change nothing");
}

fn camera_solution(c: &Contract) {
    let solve = "/v1/camera-solution";
    let eye = c.ok("GET", "/v1/cameras/{name}", "/v1/cameras/eye", None);
    let camera = winged::model::Camera::new(
        winged::model::Pose {
            position: glam::DVec3::new(
                eye["pose"]["position"][0].as_f64().expect("x"),
                eye["pose"]["position"][1].as_f64().expect("y"),
                eye["pose"]["position"][2].as_f64().expect("z"),
            ),
            rotation: glam::DQuat::from_array(
                [0, 1, 2, 3].map(|k| eye["pose"]["rotation"][k].as_f64().expect("q")),
            ),
        },
        serde_json::from_value(eye["intrinsics"].clone()).expect("intrinsics"),
    )
    .expect("the eye camera");
    // Points in front of the eye, seen where it sees them.
    let target = camera.pose.position + 3.0 * camera.view_direction();
    let correspondences: Vec<Value> = (0..12)
        .map(|i| {
            let p = target
                + glam::DVec3::new(
                    (i % 3) as f64 * 0.4 - 0.4,
                    (i / 3 % 2) as f64 * 0.5 - 0.25,
                    (i / 6) as f64 * 0.3 + (i % 2) as f64 * 0.1,
                );
            let px = camera.project(p).expect("in front");
            json!({"pixel": px.to_array(), "point": p.to_array()})
        })
        .collect();
    let before = c.revision();
    let got = c.ok(
        "POST",
        solve,
        solve,
        Some(json!({"intrinsics": "eye", "correspondences": correspondences})),
    );
    assert_eq!(got["revision"], before, "{got}");
    assert_eq!(got["inliers"].as_array().map(Vec::len), Some(12), "{got}");
    assert!(got.get("stored_as").is_none());
    let stored = c.ok(
        "POST",
        solve,
        solve,
        Some(json!({
            "intrinsics": eye["intrinsics"],
            "correspondences": correspondences,
            "store_as": "solved",
            "threshold_px": 2,
            "seed": 1,
        })),
    );
    assert_eq!(stored["stored_as"], "solved");
    assert_eq!(stored["revision"], before + 1, "{stored}");
    assert_eq!(c.revision(), before + 1, "store_as is one write");
    c.ok("GET", "/v1/cameras/{name}", "/v1/cameras/solved", None);
    c.ok("DELETE", "/v1/cameras/{name}", "/v1/cameras/solved", None);
    let focal = c.ok(
        "POST",
        solve,
        solve,
        Some(json!({"intrinsics": "eye", "correspondences": correspondences, "solve_focal": true})),
    );
    assert!(focal["focal"]["fx"].is_f64(), "{focal}");
    // From a picture: a blank one shows no edges to align with.
    let blank = {
        use base64::Engine as _;
        let mut png = Vec::new();
        let mut encoder = png::Encoder::new(&mut png, 640, 480);
        encoder.set_color(png::ColorType::Grayscale);
        encoder
            .write_header()
            .expect("a header")
            .write_image_data(&vec![90u8; 640 * 480])
            .expect("pixels");
        base64::engine::general_purpose::STANDARD.encode(png)
    };
    let p = c.refused_json(
        "POST",
        solve,
        solve,
        json!({"image": blank, "initial": "eye"}),
        422,
        Spec::Either,
    );
    assert_eq!(p["type"], "urn:winged:problem:no-image-edges", "{p}");
    c.refused_json(
        "POST",
        solve,
        solve,
        json!({"image": "not base64!", "initial": "eye"}),
        400,
        Spec::Either,
    );
    c.refused_json(
        "POST",
        solve,
        solve,
        json!({"image": blank, "initial": "eye", "intrinsics": "eye"}),
        400,
        Spec::Refuses,
    );

    c.refused_json(
        "POST",
        solve,
        solve,
        json!({"intrinsics": "eye", "correspondences": correspondences[..3]}),
        422,
        Spec::Either,
    );
    c.refused_json(
        "POST",
        solve,
        solve,
        json!({"intrinsics": "eye", "correspondences": [{"pixel": [1, 2], "vertex": 987_654_321u64}]}),
        422,
        Spec::Either,
    );
    c.refused_json(
        "POST",
        solve,
        solve,
        json!({"intrinsics": "nobody", "correspondences": correspondences}),
        404,
        Spec::Either,
    );
    c.refused_json(
        "POST",
        solve,
        solve,
        json!({"intrinsics": "eye", "correspondences": [{"pixel": [1, 2]}]}),
        400,
        Spec::Refuses,
    );
    c.refused_json(
        "POST",
        solve,
        solve,
        json!({"intrinsics": "eye", "correspondences": correspondences, "focal": 1}),
        400,
        Spec::Refuses,
    );
}

fn spatial(c: &Contract) {
    let (sphere, boxed, nearest, ray) = (
        "/v1/spatial/sphere",
        "/v1/spatial/box",
        "/v1/spatial/nearest",
        "/v1/spatial/ray",
    );
    // A read: the revision stays, and GET and POST answer alike.
    let before = c.revision();
    let got = c.ok("GET", sphere, "/v1/spatial/sphere?x=0&y=0&z=0.5&r=3", None);
    assert_eq!(got["revision"], before, "{got}");
    assert!(
        !got["bodies"].as_array().expect("bodies").is_empty(),
        "{got}"
    );
    let posted = c.ok(
        "POST",
        sphere,
        sphere,
        Some(json!({"center": [0, 0, 0.5], "radius": 3})),
    );
    assert_eq!(posted, got);
    c.ok(
        "POST",
        sphere,
        sphere,
        Some(json!({"center": [0, 0, 0.5], "radius": 1, "detail": "portions", "tolerance": 0.01})),
    );
    c.ok(
        "GET",
        sphere,
        "/v1/spatial/sphere?x=0&y=0&z=0&r=1&detail=bodies&max_features=10",
        None,
    );
    c.ok(
        "GET",
        boxed,
        "/v1/spatial/box?min_x=-1&min_y=-1&min_z=0&max_x=1&max_y=1&max_z=1&detail=portions",
        None,
    );
    c.ok(
        "POST",
        boxed,
        boxed,
        Some(json!({"min": [-1, -1, 0], "max": [1, 1, 1], "detail": "features"})),
    );
    let n = c.ok("GET", nearest, "/v1/spatial/nearest?x=0&y=0&z=10", None);
    assert!(n["hit"]["id"].is_u64(), "{n}");
    let none = c.ok(
        "POST",
        nearest,
        nearest,
        Some(json!({"point": [0, 0, 1000], "max_distance": 1})),
    );
    assert!(none["hit"].is_null(), "{none}");
    let down = c.ok(
        "GET",
        ray,
        "/v1/spatial/ray?x=0&y=0&z=10&dx=0&dy=0&dz=-1",
        None,
    );
    assert!(down["hit"]["face"].is_u64(), "{down}");
    let up = c.ok(
        "POST",
        ray,
        ray,
        Some(json!({"origin": [0, 0, 100], "direction": [0, 0, 1]})),
    );
    assert!(up["hit"].is_null(), "{up}");
    assert_eq!(c.revision(), before, "spatial queries are reads");

    let nan = "/v1/spatial/sphere?x=NaN&y=0&z=0&r=1";
    c.refused("GET", sphere, nan, Send::Nothing, 422, Spec::Either);
    let missing = "/v1/spatial/sphere?x=0&y=0&z=0";
    c.refused("GET", sphere, missing, Send::Nothing, 400, Spec::Either);
    c.refused_json(
        "POST",
        sphere,
        sphere,
        json!({"center": [0, 0, 0], "radius": -1}),
        422,
        Spec::Either,
    );
    c.refused_json(
        "POST",
        sphere,
        sphere,
        json!({"center": [0, 0, 0], "radius": 1, "colour": "red"}),
        400,
        Spec::Refuses,
    );
    let many = c.refused_json(
        "POST",
        sphere,
        sphere,
        json!({"center": [0, 0, 0.5], "radius": 3, "max_features": 1}),
        422,
        Spec::Either,
    );
    assert_eq!(many["type"], "urn:winged:problem:too-many-features");
    let empty = "/v1/spatial/box?min_x=1&min_y=0&min_z=0&max_x=0&max_y=1&max_z=1";
    c.refused("GET", boxed, empty, Send::Nothing, 422, Spec::Either);
    c.refused_json(
        "POST",
        boxed,
        boxed,
        json!({"min": [0, 0], "max": [1, 1, 1]}),
        400,
        Spec::Refuses,
    );
    let far = "/v1/spatial/nearest?x=0&y=0&z=0&max_distance=-1";
    c.refused("GET", nearest, far, Send::Nothing, 422, Spec::Either);
    c.refused_json(
        "POST",
        nearest,
        nearest,
        json!({"point": [0, 0, 0], "near": true}),
        400,
        Spec::Refuses,
    );
    let zero = "/v1/spatial/ray?x=0&y=0&z=0&dx=0&dy=0&dz=0";
    c.refused("GET", ray, zero, Send::Nothing, 422, Spec::Either);
    c.refused_json(
        "POST",
        ray,
        ray,
        json!({"origin": [0, 0, 0]}),
        400,
        Spec::Refuses,
    );
}

fn lights(c: &Contract) {
    let (one, list) = ("/v1/lights/{name}", "/v1/lights");
    let ls = c.ok("GET", list, list, None);
    assert_eq!(ls["lights"][0]["name"], "sun", "{ls}");
    let sun = c.ok("GET", one, "/v1/lights/sun", None);
    assert_eq!(sun["type"], "sun");
    c.ok(
        "PUT",
        one,
        "/v1/lights/lamp",
        Some(json!({"type": "point", "position": [0, 0, 3]})),
    );
    let lamp = c.ok("GET", one, "/v1/lights/lamp", None);
    assert_eq!(
        lamp["intensity"].as_f64(),
        Some(1.0),
        "the default intensity: {lamp}"
    );
    c.ok(
        "PUT",
        one,
        "/v1/lights/dusk",
        Some(json!({"type": "sun", "direction": [1, 0, -1], "intensity": 0.5})),
    );
    let ls = c.ok("GET", list, list, None);
    assert_eq!(ls["lights"].as_array().map(Vec::len), Some(3), "{ls}");

    let p = "/v1/lights/bad";
    let no =
        |body: Value, status: u16, spec: Spec| c.refused_json("PUT", one, p, body, status, spec);
    let dark = no(
        json!({"type": "sun", "direction": [0, 0, 0]}),
        422,
        Spec::Either,
    );
    assert_eq!(dark["type"], "urn:winged:problem:invalid-light");
    no(
        json!({"type": "sun", "direction": [0, 0, -1], "intensity": -1}),
        422,
        Spec::Refuses,
    );
    no(
        json!({"type": "laser", "direction": [0, 0, -1]}),
        400,
        Spec::Refuses,
    );
    no(
        json!({"type": "point", "direction": [0, 0, -1]}),
        400,
        Spec::Refuses,
    );
    no(json!({"direction": [0, 0, -1]}), 400, Spec::Refuses);
    c.refused(
        "PUT",
        one,
        p,
        Send::Raw(Some("text/plain"), b"{}"),
        415,
        Spec::Either,
    );
    c.refused(
        "GET",
        one,
        "/v1/lights/nowhere",
        Send::Nothing,
        404,
        Spec::Either,
    );

    c.ok("DELETE", one, "/v1/lights/lamp", None);
    c.refused(
        "DELETE",
        one,
        "/v1/lights/lamp",
        Send::Nothing,
        404,
        Spec::Either,
    );

    let w = c.ok("GET", "/v1/world", "/v1/world", None);
    assert_eq!(
        (w["cameras"].as_u64(), w["lights"].as_u64()),
        (Some(2), Some(2)),
        "{w}"
    );
}

fn deletes(c: &Contract) {
    let t = "/v1/bodies/{id}";
    let table = body_named(c, "table");
    let parts = c.ok("GET", t, &format!("/v1/bodies/{table}"), None)["parts"].clone();
    let gone = c.ok("DELETE", t, &format!("/v1/bodies/{table}"), None);
    let killed = ids(&gone["killed"]);
    assert!(killed.contains(&table), "{gone}");
    assert!(
        ids(&parts).iter().all(|p| killed.contains(p)),
        "parts die too: {gone}"
    );
    c.refused(
        "GET",
        t,
        &format!("/v1/bodies/{table}"),
        Send::Nothing,
        404,
        Spec::Either,
    );
    c.refused(
        "DELETE",
        t,
        &format!("/v1/bodies/{table}"),
        Send::Nothing,
        404,
        Spec::Either,
    );
    c.refused(
        "DELETE",
        t,
        "/v1/bodies/1",
        Send::Nothing,
        422,
        Spec::Either,
    );
    c.refused(
        "DELETE",
        t,
        "/v1/bodies/x",
        Send::Nothing,
        400,
        Spec::Either,
    );
}

fn unknown_route(c: &Contract) {
    let r = c.http.call("GET", "/v1/nowhere", Send::Nothing);
    assert_eq!(
        (r.status, r.media_type.as_str()),
        (404, "application/problem+json")
    );
    let v = Validator::new(&c.doc);
    let problem = json!({"$ref": "#/components/schemas/Problem"});
    v.validate(&problem, &r.json()).expect("a problem");
}

/// The changes since `start`, the event stream, metrics and a snapshot on request.
fn following(c: &Contract, start: u64) {
    let now = c.revision();
    let all = c.ok(
        "GET",
        "/v1/world/changes",
        &format!("/v1/world/changes?since={start}&limit=10000"),
        None,
    );
    assert_eq!(all["resync"], false, "{all}");
    let revisions: Vec<u64> = all["changes"]
        .as_array()
        .expect("changes")
        .iter()
        .map(|ch| id(&ch["revision"]))
        .collect();
    assert_eq!(revisions, (start + 1..=now).collect::<Vec<_>>());
    let ahead = c.ok(
        "GET",
        "/v1/world/changes",
        &format!("/v1/world/changes?since={}", now + 1),
        None,
    );
    assert_eq!(ahead["resync"], true);
    c.refused(
        "GET",
        "/v1/world/changes",
        "/v1/world/changes",
        Send::Nothing,
        400,
        Spec::Either,
    );
    // A stream from before the history kept sends one `resync` event and ends.
    let stream = c.ok_text("GET", "/v1/world/events", "/v1/world/events?since=0");
    assert!(stream.contains("event: resync"), "{stream}");
    let metrics = c.ok_text("GET", "/metrics", "/metrics");
    assert!(metrics.contains("winged_http_requests_total"), "{metrics}");
    assert!(metrics.ends_with("# EOF\n"), "{metrics}");
    let snap = c.ok("POST", "/v1/admin/snapshot", "/v1/admin/snapshot", None);
    assert_eq!(snap["revision"], now);
}

/// The events of a Server-Sent Events text, each as an object of its fields (`event`,
/// `id`, `data`; comment lines skipped, several `data` lines joined by newlines).
fn sse_events(text: &str) -> Vec<Value> {
    let mut events = Vec::new();
    for block in text.split("\n\n") {
        let mut event = serde_json::Map::new();
        for line in block
            .lines()
            .filter(|l| !l.is_empty() && !l.starts_with(':'))
        {
            let (field, value) = line.split_once(':').unwrap_or((line, ""));
            let value = value.strip_prefix(' ').unwrap_or(value);
            match event.get_mut(field) {
                Some(Value::String(old)) if field == "data" => {
                    old.push('\n');
                    old.push_str(value);
                }
                _ => {
                    event.insert(field.to_owned(), Value::String(value.to_owned()));
                }
            }
        }
        if !event.is_empty() {
            events.push(Value::Object(event));
        }
    }
    events
}
