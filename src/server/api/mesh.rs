//! Mesh files in and out: `POST /v1/bodies` with a `mesh` shape, `POST
//! /v1/bodies/import` with the file as the request body, `GET /v1/bodies/{id}/mesh` and
//! `GET /v1/world/mesh`.
//!
//! A file is read and its bodies built on a blocking thread (never on the world's
//! owner, never on the async threads); the owner takes one [`Edit::ImportBodies`] with
//! the bodies' polygons, so the journal keeps the geometry, not the file.

use axum::Json;
use axum::extract::{Request, State};
use axum::http::StatusCode;
use axum::http::header::{CONTENT_DISPOSITION, CONTENT_TYPE, ETAG};
use axum::response::{IntoResponse, Response};
use base64::Engine as _;
use serde::{Deserialize, Serialize};

use super::body::Bodies;
use super::extract::{ApiPath, ApiQuery};

use super::precondition::{IfMatch, etag};
use super::{Answer, snapshot};
use crate::edit::command::{FaceList, ImportedBody};
use crate::mesh::write::{ExportError, Frame};
use crate::mesh::{Format, ImportError, Imported};
use crate::model::{BodyId, Color, Pose, Serial};
use crate::server::actor::{Applied, Handle};
use crate::server::problem::Problem;
use crate::server::request::{HexColor, MeshCreate, MeshOptions};

/// `POST /v1/bodies` with `shape.type = "mesh"`: the file decoded from base64 and
/// imported.
pub(super) async fn create(h: &Handle, req: MeshCreate, expected: Option<u64>) -> Answer {
    let options = req
        .shape
        .options
        .to_import()
        .map_err(Problem::bad_request)?;
    let format = req.shape.format;
    let data = req.shape.data;
    let size = data.len() / 4 * 3;
    let place = Place {
        name: req.name,
        parent: req.parent,
        pose: req.pose,
        color: req.color,
    };
    let started = std::time::Instant::now();
    let imported = off_the_owner(move || {
        let bytes = base64::engine::general_purpose::STANDARD
            .decode(data.trim())
            .or_else(|_| base64::engine::general_purpose::STANDARD_NO_PAD.decode(data.trim()))
            .map_err(|e| Problem::bad_request(format!("shape.data is not base64: {e}")))?;
        drop(data);
        crate::mesh::import(format, &bytes, &options).map_err(import_problem)
    })
    .await;
    let imported = logged(format, size, started, imported)?;
    place_bodies(h, imported, place, expected, started).await
}

/// `POST /v1/bodies/import`'s query (its fields listed, not flattened: the query
/// string's numbers and booleans are typed by the field they land in).
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct ImportQuery {
    format: Format,
    #[serde(default)]
    name: Option<String>,
    #[serde(default)]
    parent: Option<u64>,
    #[serde(default)]
    color: Option<HexColor>,
    #[serde(default)]
    unit: Option<crate::mesh::Unit>,
    #[serde(default)]
    merge_coplanar: Option<bool>,
    #[serde(default)]
    weld: Option<f64>,
    #[serde(default)]
    coplanar_tolerance: Option<f64>,
    #[serde(default)]
    check_intersections: Option<bool>,
    #[serde(default)]
    expected_revision: Option<u64>,
}

/// `POST /v1/bodies/import?format=…`: the request body is the file itself. The body is
/// read before the query is judged, so that a refusal leaves the connection usable.
pub(super) async fn import(State(h): State<Handle>, req: Request) -> Answer {
    let uri = req.uri().clone();
    let header = IfMatch::from_headers(req.headers());
    let bytes = Bodies::of(&req)?
        .parse(req, |bytes| Ok(bytes.to_vec()))
        .await?;
    let IfMatch(header) = header?;
    let q = axum::extract::Query::<ImportQuery>::try_from_uri(&uri)
        .map_err(|e| Problem::bad_request(e.body_text()))?
        .0;
    let options = MeshOptions {
        unit: q.unit,
        merge_coplanar: q.merge_coplanar,
        weld: q.weld,
        coplanar_tolerance: q.coplanar_tolerance,
        check_intersections: q.check_intersections,
    };
    let expected = match (header, q.expected_revision) {
        (Some(a), Some(b)) if a != b => {
            return Err(Problem::bad_request(format!(
                "If-Match names revision {a} but expected_revision is {b}"
            )));
        }
        (a, b) => a.or(b),
    };
    let options = options.to_import().map_err(Problem::bad_request)?;
    let format = q.format;
    let size = bytes.len();
    let started = std::time::Instant::now();
    let imported = off_the_owner(move || {
        crate::mesh::import(format, &bytes, &options).map_err(import_problem)
    })
    .await;
    let imported = logged(format, size, started, imported)?;
    let place = Place {
        name: q.name,
        parent: q.parent,
        pose: None,
        color: q.color.map(|c| c.0),
    };
    place_bodies(&h, imported, place, expected, started).await
}

/// Logs how reading and building a file of `size` bytes ended, `started` being when it
/// began.
fn logged(
    format: Format,
    size: usize,
    started: std::time::Instant,
    imported: Result<Imported, Problem>,
) -> Result<Imported, Problem> {
    let elapsed_ms = started.elapsed().as_secs_f64() * 1e3;
    match &imported {
        Ok(i) => tracing::info!(
            format = ?format,
            bytes = size,
            bodies = i.bodies.len(),
            faces = i.bodies.iter().map(|b| b.faces.len()).sum::<usize>(),
            elapsed_ms,
            "mesh read and built"
        ),
        Err(p) => tracing::info!(
            format = ?format,
            bytes = size,
            elapsed_ms,
            problem = %p.detail,
            "mesh refused"
        ),
    }
    imported
}

/// Runs `work` on a blocking thread.
async fn off_the_owner<T: Send + 'static>(
    work: impl FnOnce() -> Result<T, Problem> + Send + 'static,
) -> Result<T, Problem> {
    tokio::task::spawn_blocking(work)
        .await
        .map_err(Problem::internal)?
}

/// Where a request puts a file's bodies.
struct Place {
    /// The first body's name, over the file's.
    name: Option<String>,
    /// The supart of the top-level bodies.
    parent: Option<u64>,
    /// Composed before each top-level body's pose.
    pose: Option<Pose>,
    /// Every body's colour, over the file's.
    color: Option<Color>,
}

/// One body an import made, in the answer.
#[derive(Serialize)]
struct ImportedDto {
    id: u64,
    #[serde(skip_serializing_if = "Option::is_none")]
    name: Option<String>,
    parent: u64,
    faces: usize,
    edges: usize,
    vertices: usize,
    volume: f64,
    /// The object of the file it came from.
    object: usize,
    /// How many of the file's faces made it.
    faces_read: usize,
    /// Coplanar regions left unmerged (their outline is not one ring).
    unmerged: usize,
}

#[derive(Serialize)]
struct ImportAnswer {
    /// The first body's id and counts.
    id: u64,
    faces: usize,
    edges: usize,
    vertices: usize,
    bodies: Vec<ImportedDto>,
    revision: u64,
}

/// Sends the bodies to the world's owner as one edit and answers 201 with them.
async fn place_bodies(
    h: &Handle,
    imported: Imported,
    place: Place,
    expected: Option<u64>,
    started: std::time::Instant,
) -> Answer {
    let Imported { bodies, built } = imported;
    let mut edits = Vec::with_capacity(bodies.len());
    let mut about = Vec::with_capacity(bodies.len());
    for (k, b) in bodies.into_iter().enumerate() {
        let top = b.parent.is_none();
        let name = if k == 0 && place.name.is_some() {
            place.name.clone()
        } else {
            b.name
        };
        let pose = match (top, place.pose) {
            (true, Some(p)) => p.compose(&b.pose),
            _ => b.pose,
        };
        about.push((name.clone(), b.object, b.faces_read, b.unmerged));
        let mut faces = FaceList::new();
        for f in b.faces.iter() {
            faces.push(f);
        }
        edits.push(ImportedBody {
            name,
            parent: if top { place.parent } else { None },
            within: b.parent,
            pose: (pose != Pose::IDENTITY).then_some(pose),
            color: place.color.or(b.color),
            vertices: b.positions,
            faces,
        });
    }
    let planned = crate::edit::plan_import(edits, built).map_err(Problem::internal)?;
    let placing = std::time::Instant::now();
    let Applied { outcome, revision } = h.apply_planned_if(planned, expected).await?;
    tracing::info!(
        revision,
        placed_ms = placing.elapsed().as_secs_f64() * 1e3,
        total_ms = started.elapsed().as_secs_f64() * 1e3,
        "mesh import placed"
    );
    let placed = outcome.pieces.unwrap_or_default();
    let snapshot = snapshot(h).await.ok();
    let bodies: Vec<ImportedDto> = placed
        .into_iter()
        .zip(about)
        .map(|(p, (name, object, faces_read, unmerged))| ImportedDto {
            id: p.id,
            name,
            parent: snapshot
                .as_ref()
                .and_then(|w| w.supart(BodyId(Serial(p.id))))
                .map_or(0, |s| s.get()),
            faces: p.faces,
            edges: p.edges,
            vertices: p.vertices,
            volume: p.volume,
            object,
            faces_read,
            unmerged,
        })
        .collect();
    let first = bodies.first();
    let answer = ImportAnswer {
        id: first.map_or(0, |b| b.id),
        faces: first.map_or(0, |b| b.faces),
        edges: first.map_or(0, |b| b.edges),
        vertices: first.map_or(0, |b| b.vertices),
        bodies,
        revision,
    };
    Ok((StatusCode::CREATED, [(ETAG, etag(revision))], Json(answer)).into_response())
}

/// The problem answer for a file that was not imported.
fn import_problem(e: ImportError) -> Problem {
    let detail = e.to_string();
    match e {
        ImportError::Parse { format, .. } => Problem::new(
            StatusCode::UNPROCESSABLE_ENTITY,
            "mesh-unreadable",
            "Mesh file unreadable",
            detail,
        )
        .with_member("format", format.into()),
        ImportError::Unsupported { .. } => Problem::new(
            StatusCode::UNPROCESSABLE_ENTITY,
            "mesh-unsupported",
            "Mesh feature not supported",
            detail,
        ),
        ImportError::TooLarge { .. } => Problem::new(
            StatusCode::PAYLOAD_TOO_LARGE,
            "too-large",
            "Mesh too large",
            detail,
        ),
        ImportError::Empty => Problem::new(
            StatusCode::UNPROCESSABLE_ENTITY,
            "mesh-empty",
            "Mesh file empty",
            detail,
        ),
        ImportError::Invalid { defect, at, .. } => Problem::new(
            StatusCode::UNPROCESSABLE_ENTITY,
            "mesh-invalid",
            "Mesh not a closed polyhedron",
            detail,
        )
        .with_member("defect", serde_json::to_value(defect).unwrap_or_default())
        .with_member("where", serde_json::to_value(&*at).unwrap_or_default()),
    }
}

/// `GET /v1/bodies/{id}/mesh`'s query.
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct ExportQuery {
    #[serde(default = "default_format")]
    format: Format,
    #[serde(default = "default_frame")]
    frame: Frame,
}

fn default_format() -> Format {
    Format::Obj
}

fn default_frame() -> Frame {
    Frame::World
}

/// `GET /v1/bodies/{id}/mesh?format=obj|stl|ply|off|glb|3mf&frame=world|body`.
pub(super) async fn export_body(
    State(h): State<Handle>,
    ApiPath(id): ApiPath<u64>,
    ApiQuery(q): ApiQuery<ExportQuery>,
) -> Answer {
    let w = snapshot(&h).await?;
    let b = BodyId(Serial(id));
    if w.node(b).is_none() || b == w.root() {
        return Err(Problem::not_found(format!("no body has id {id}")));
    }
    let revision = w.revision();
    let name = w.name(b).map(str::to_owned);
    let format = q.format;
    let bytes = off_the_owner(move || {
        crate::mesh::write::body(&w, b, format, q.frame).map_err(export_problem)
    })
    .await?;
    let stem = name.unwrap_or_else(|| format!("body-{id}"));
    Ok(file(bytes, format, &stem, revision))
}

/// `GET /v1/world/mesh`'s query.
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct WorldQuery {
    #[serde(default = "default_world_format")]
    format: Format,
}

fn default_world_format() -> Format {
    Format::Glb
}

/// `GET /v1/world/mesh?format=glb`: the whole world, its parts tree as the node
/// hierarchy.
pub(super) async fn export_world(
    State(h): State<Handle>,
    ApiQuery(q): ApiQuery<WorldQuery>,
) -> Answer {
    if q.format != Format::Glb {
        return Err(Problem::bad_request(format!(
            "the world is written as glb (its parts tree as glTF's node hierarchy), not {}; \
             GET /v1/bodies/{{id}}/mesh writes one body in any format",
            q.format.name()
        )));
    }
    let w = snapshot(&h).await?;
    let revision = w.revision();
    let bytes =
        off_the_owner(move || crate::mesh::write::world_glb(&w).map_err(export_problem)).await?;
    Ok(file(bytes, Format::Glb, "world", revision))
}

/// A file answer: its media type, a download name and the revision it shows.
fn file(bytes: Vec<u8>, format: Format, stem: &str, revision: u64) -> Response {
    let safe: String = stem
        .chars()
        .map(|c| {
            if c.is_ascii_alphanumeric() || c == '-' || c == '_' || c == '.' {
                c
            } else {
                '_'
            }
        })
        .collect();
    let disposition = format!("attachment; filename=\"{safe}.{}\"", format.name());
    (
        [
            (CONTENT_TYPE, format.media_type().to_owned()),
            (CONTENT_DISPOSITION, disposition),
            (ETAG, etag(revision).to_str().unwrap_or_default().to_owned()),
        ],
        bytes,
    )
        .into_response()
}

fn export_problem(e: ExportError) -> Problem {
    match e {
        ExportError::NotFound(id) => Problem::not_found(format!("no body has id {id}")),
        ExportError::Unsupported(detail) => Problem::bad_request(detail),
        ExportError::Encode { .. } => Problem::internal(e),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh::ImportOptions;

    #[test]
    fn an_invalid_mesh_names_the_defect_and_where() {
        let e = crate::mesh::import(
            Format::Off,
            b"OFF\n4 3 0\n0 0 0\n1 0 0\n0 1 0\n0 0 1\n3 0 2 1\n3 0 1 3\n3 0 3 2\n",
            &ImportOptions::default(),
        )
        .expect_err("open");
        let p = import_problem(e);
        assert_eq!(p.status, StatusCode::UNPROCESSABLE_ENTITY);
        let json: serde_json::Value = serde_json::from_slice(&p.to_json()).expect("json");
        assert_eq!(json["defect"], "open");
        assert_eq!(json["where"]["object"], 0);
        assert!(
            json["where"]["vertices"]
                .as_array()
                .is_some_and(|v| v.len() == 2),
            "{json}"
        );
    }
}
