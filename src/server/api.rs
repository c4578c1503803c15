//! The HTTP surface: routes, request parsing and answers. Writes become [`Edit`]s sent to
//! the actor; reads work on a snapshot.

use std::sync::Arc;

use axum::extract::rejection::{JsonRejection, PathRejection, QueryRejection};
use axum::extract::{DefaultBodyLimit, Extension, Path, Query, State};
use axum::http::StatusCode;
use axum::response::{IntoResponse, Response};
use axum::routing::{get, post};
use axum::{Json, Router};
use serde::{Deserialize, Serialize};
use serde_json::json;

use super::actor::{Applied, Handle};
use super::dto::{
    BodyDto, CameraDto, CameraReq, CopyReq, CreateBody, EdgeDto, EulerOp, FaceDto, LightDto,
    PatchBody, SweepReq, TopologyDto, TransformReq, VertexDto, euler_of,
};
use super::edit::{Edit, Outcome};
use super::problem::Problem;
use crate::model::{BodyId, Serial, World};

/// The largest request body accepted, in bytes (a polyhedron upload is the big one).
pub const MAX_REQUEST_BYTES: usize = 64 * 1024 * 1024;

/// The router over a running actor.
pub fn router(handle: Handle) -> Router {
    Router::new()
        .route("/healthz", get(healthz))
        .route("/openapi.json", get(openapi))
        .route("/v1/world", get(world))
        .route("/v1/bodies", get(list_bodies).post(create_body))
        .route(
            "/v1/bodies/{id}",
            get(get_body).patch(patch_body).delete(delete_body),
        )
        .route("/v1/bodies/{id}/topology", get(topology))
        .route("/v1/bodies/{id}/euler", post(euler))
        .route("/v1/bodies/{id}/transform", post(transform))
        .route("/v1/bodies/{id}/sweep", post(sweep))
        .route("/v1/bodies/{id}/dual", post(dual))
        .route("/v1/bodies/{id}/evert", post(evert))
        .route("/v1/bodies/{id}/copy", post(copy))
        .route("/v1/cameras", get(list_cameras))
        .route(
            "/v1/cameras/{name}",
            get(get_camera).put(put_camera).delete(delete_camera),
        )
        .route("/v1/lights", get(list_lights))
        .route(
            "/v1/lights/{name}",
            get(get_light).put(put_light).delete(delete_light),
        )
        .fallback(not_found)
        .layer(Extension(HeavyReads::for_this_machine()))
        .layer(DefaultBodyLimit::max(MAX_REQUEST_BYTES))
        .with_state(handle)
}

type Answer = Result<Response, Problem>;

/// The gate heavy reads (topology dumps) pass: one permit per core but one, at least one.
#[derive(Clone)]
struct HeavyReads(Arc<tokio::sync::Semaphore>);

impl HeavyReads {
    fn for_this_machine() -> Self {
        let cores = std::thread::available_parallelism().map_or(2, |n| n.get());
        HeavyReads(Arc::new(tokio::sync::Semaphore::new(
            cores.saturating_sub(1).max(1),
        )))
    }
}

/// A write's answer: the outcome's fields and the revision.
#[derive(Serialize)]
struct Written {
    #[serde(flatten)]
    outcome: Outcome,
    revision: u64,
}

async fn write(h: &Handle, edit: Edit, status: StatusCode) -> Answer {
    let Applied { outcome, revision } =
        h.apply(edit).await.map_err(|_| Problem::unavailable())??;
    Ok((status, Json(Written { outcome, revision })).into_response())
}

async fn snapshot(h: &Handle) -> Result<Arc<World>, Problem> {
    h.snapshot().await.map_err(|_| Problem::unavailable())
}

fn id_of(p: Result<Path<u64>, PathRejection>) -> Result<u64, Problem> {
    p.map(|Path(id)| id).map_err(Problem::from)
}

fn name_of(p: Result<Path<String>, PathRejection>) -> Result<String, Problem> {
    p.map(|Path(n)| n).map_err(Problem::from)
}

fn json_of<T>(j: Result<Json<T>, JsonRejection>) -> Result<T, Problem> {
    j.map(|Json(t)| t).map_err(Problem::from)
}

async fn not_found() -> Problem {
    Problem::not_found("no such route; see /openapi.json")
}

async fn healthz(State(h): State<Handle>) -> Answer {
    let w = snapshot(&h).await?;
    Ok(Json(json!({"status": "ok", "revision": w.revision()})).into_response())
}

async fn openapi() -> Response {
    (
        [(axum::http::header::CONTENT_TYPE, "application/json")],
        super::spec::openapi_json(),
    )
        .into_response()
}

async fn world(State(h): State<Handle>) -> Answer {
    let w = snapshot(&h).await?;
    let (mut f, mut e, mut v) = (0, 0, 0);
    for (_, node) in w.bodies() {
        f += node.body.face_count();
        e += node.body.edge_count();
        v += node.body.vertex_count();
    }
    Ok(Json(json!({
        "revision": w.revision(),
        "bodies": w.body_count(),
        "faces": f,
        "edges": e,
        "vertices": v,
        "cameras": w.cameras().count(),
        "lights": w.lights().count(),
    }))
    .into_response())
}

fn body_dto(w: &World, b: BodyId) -> Option<BodyDto> {
    let node = w.node(b)?;
    let body = &node.body;
    Some(BodyDto {
        id: b.get(),
        name: node.name.clone(),
        parent: node.supart.get(),
        parts: node.parts.iter().map(|p| p.get()).collect(),
        pose: node.pose.into(),
        world_pose: w.world_pose(b)?.into(),
        euler: euler_of(body),
        volume: body.volume(),
        area: body.surface_area(),
        bounds: body.bounds().map(Into::into),
    })
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct ListQuery {
    name: Option<String>,
    parent: Option<u64>,
}

async fn list_bodies(
    State(h): State<Handle>,
    q: Result<Query<ListQuery>, QueryRejection>,
) -> Answer {
    let Query(q) = q?;
    let w = snapshot(&h).await?;
    let revision = w.revision();
    let bodies: Vec<BodyDto> = tokio::task::spawn_blocking(move || {
        w.bodies()
            .filter(|(id, _)| *id != w.root())
            .filter(|(_, node)| q.name.is_none() || node.name.as_deref() == q.name.as_deref())
            .filter(|(_, node)| q.parent.is_none_or(|p| node.supart.get() == p))
            .filter_map(|(id, _)| body_dto(&w, id))
            .collect()
    })
    .await
    .map_err(|e| {
        Problem::new(
            StatusCode::INTERNAL_SERVER_ERROR,
            "internal",
            "Internal error",
            e.to_string(),
        )
    })?;
    Ok(Json(json!({ "bodies": bodies, "revision": revision })).into_response())
}

async fn get_body(State(h): State<Handle>, id: Result<Path<u64>, PathRejection>) -> Answer {
    let id = id_of(id)?;
    let w = snapshot(&h).await?;
    let dto = body_dto(&w, BodyId(Serial(id)))
        .ok_or_else(|| Problem::not_found(format!("no body has id {id}")))?;
    let mut v = serde_json::to_value(dto).map_err(|e| Problem::bad_request(e.to_string()))?;
    v["revision"] = json!(w.revision());
    Ok(Json(v).into_response())
}

async fn topology(
    State(h): State<Handle>,
    Extension(heavy): Extension<HeavyReads>,
    id: Result<Path<u64>, PathRejection>,
) -> Answer {
    let id = id_of(id)?;
    // At most one heavy read per spare core at a time, so that small reads keep a core.
    let _permit = heavy
        .0
        .acquire()
        .await
        .map_err(|_| Problem::unavailable())?;
    let w = snapshot(&h).await?;
    let b = BodyId(Serial(id));
    if w.node(b).is_none() {
        return Err(Problem::not_found(format!("no body has id {id}")));
    }
    // A big body's dump is long work: do it off the async threads.
    let bytes = tokio::task::spawn_blocking(move || {
        let dto = topology_dto(&w, b);
        serde_json::to_vec(&dto)
    })
    .await
    .map_err(|e| {
        Problem::new(
            StatusCode::INTERNAL_SERVER_ERROR,
            "internal",
            "Internal error",
            e.to_string(),
        )
    })?
    .map_err(|e| {
        Problem::new(
            StatusCode::INTERNAL_SERVER_ERROR,
            "internal",
            "Internal error",
            e.to_string(),
        )
    })?;
    Ok((
        [(axum::http::header::CONTENT_TYPE, "application/json")],
        bytes,
    )
        .into_response())
}

fn topology_dto(w: &World, b: BodyId) -> TopologyDto {
    let body = w.body(b).expect("checked by the caller");
    let es = |e: crate::model::EdgeId| {
        if e.is_none() {
            None
        } else {
            Some(body.edge_serial(e).get())
        }
    };
    let vertices = body
        .vertices()
        .map(|v| VertexDto {
            id: body.vertex_serial(v).get(),
            position: body.position(v).to_array(),
            ped: es(body.vertex(v).ped),
        })
        .collect();
    let edges = body
        .edges()
        .map(|e| {
            let r = body.edge(e);
            let s = |x| body.edge_serial(x).get();
            EdgeDto {
                id: body.edge_serial(e).get(),
                nvt: body.vertex_serial(r.nvt()).get(),
                pvt: body.vertex_serial(r.pvt()).get(),
                nface: body.face_serial(r.nface()).get(),
                pface: body.face_serial(r.pface()).get(),
                ncw: s(r.ncw()),
                pcw: s(r.pcw()),
                nccw: s(r.nccw()),
                pccw: s(r.pccw()),
            }
        })
        .collect();
    let faces = body
        .faces()
        .map(|f| FaceDto {
            id: body.face_serial(f).get(),
            ped: es(body.face(f).ped),
            plane: body.face_plane(f).map(|p| {
                let n = p.normal;
                [n.x, n.y, n.z, p.offset]
            }),
            vertices: body
                .face_vertices(f)
                .map(|v| body.vertex_serial(v).get())
                .collect(),
        })
        .collect();
    TopologyDto {
        id: b.get(),
        revision: w.revision(),
        vertices,
        edges,
        faces,
    }
}

async fn create_body(
    State(h): State<Handle>,
    req: Result<Json<CreateBody>, JsonRejection>,
) -> Answer {
    write(&h, Edit::CreateBody(json_of(req)?), StatusCode::CREATED).await
}

async fn patch_body(
    State(h): State<Handle>,
    id: Result<Path<u64>, PathRejection>,
    req: Result<Json<PatchBody>, JsonRejection>,
) -> Answer {
    let (body, patch) = (id_of(id)?, json_of(req)?);
    write(&h, Edit::PatchBody { body, patch }, StatusCode::OK).await
}

async fn delete_body(State(h): State<Handle>, id: Result<Path<u64>, PathRejection>) -> Answer {
    write(&h, Edit::DeleteBody { body: id_of(id)? }, StatusCode::OK).await
}

async fn euler(
    State(h): State<Handle>,
    id: Result<Path<u64>, PathRejection>,
    req: Result<Json<EulerOp>, JsonRejection>,
) -> Answer {
    let (body, op) = (id_of(id)?, json_of(req)?);
    write(&h, Edit::Euler { body, op }, StatusCode::OK).await
}

async fn transform(
    State(h): State<Handle>,
    id: Result<Path<u64>, PathRejection>,
    req: Result<Json<TransformReq>, JsonRejection>,
) -> Answer {
    let (body, req) = (id_of(id)?, json_of(req)?);
    write(&h, Edit::Transform { body, req }, StatusCode::OK).await
}

async fn sweep(
    State(h): State<Handle>,
    id: Result<Path<u64>, PathRejection>,
    req: Result<Json<SweepReq>, JsonRejection>,
) -> Answer {
    let (body, req) = (id_of(id)?, json_of(req)?);
    write(&h, Edit::Sweep { body, req }, StatusCode::OK).await
}

async fn dual(State(h): State<Handle>, id: Result<Path<u64>, PathRejection>) -> Answer {
    write(&h, Edit::Dual { body: id_of(id)? }, StatusCode::OK).await
}

async fn evert(State(h): State<Handle>, id: Result<Path<u64>, PathRejection>) -> Answer {
    write(&h, Edit::Evert { body: id_of(id)? }, StatusCode::OK).await
}

async fn copy(
    State(h): State<Handle>,
    id: Result<Path<u64>, PathRejection>,
    req: Result<Option<Json<CopyReq>>, JsonRejection>,
) -> Answer {
    let body = id_of(id)?;
    // The body is optional: none (no Content-Type) means an unnamed copy.
    let name = req?.and_then(|Json(r)| r.name);
    write(&h, Edit::Copy { body, name }, StatusCode::CREATED).await
}

async fn list_cameras(State(h): State<Handle>) -> Answer {
    let w = snapshot(&h).await?;
    let cams: Vec<CameraDto> = w.cameras().map(|(n, c)| CameraDto::new(n, c)).collect();
    Ok(Json(json!({ "cameras": cams, "revision": w.revision() })).into_response())
}

async fn get_camera(State(h): State<Handle>, name: Result<Path<String>, PathRejection>) -> Answer {
    let name = name_of(name)?;
    let w = snapshot(&h).await?;
    let c = w
        .camera(&name)
        .ok_or_else(|| Problem::not_found(format!("no camera is named {:?}", name)))?;
    Ok(Json(CameraDto::new(&name, c)).into_response())
}

async fn put_camera(
    State(h): State<Handle>,
    name: Result<Path<String>, PathRejection>,
    req: Result<Json<CameraReq>, JsonRejection>,
) -> Answer {
    let name = name_of(name)?;
    let camera = json_of(req)?;
    write(&h, Edit::PutCamera { name, camera }, StatusCode::OK).await
}

async fn delete_camera(
    State(h): State<Handle>,
    name: Result<Path<String>, PathRejection>,
) -> Answer {
    let name = name_of(name)?;
    write(&h, Edit::DeleteCamera { name }, StatusCode::OK).await
}

async fn list_lights(State(h): State<Handle>) -> Answer {
    let w = snapshot(&h).await?;
    let lights: Vec<serde_json::Value> = w
        .lights()
        .map(|(n, l)| {
            let mut v = serde_json::to_value(LightDto::from(l)).unwrap_or_default();
            v["name"] = json!(n);
            v
        })
        .collect();
    Ok(Json(json!({ "lights": lights, "revision": w.revision() })).into_response())
}

async fn get_light(State(h): State<Handle>, name: Result<Path<String>, PathRejection>) -> Answer {
    let name = name_of(name)?;
    let w = snapshot(&h).await?;
    let l = w
        .light(&name)
        .ok_or_else(|| Problem::not_found(format!("no light is named {:?}", name)))?;
    let mut v = serde_json::to_value(LightDto::from(l)).unwrap_or_default();
    v["name"] = json!(name);
    Ok(Json(v).into_response())
}

async fn put_light(
    State(h): State<Handle>,
    name: Result<Path<String>, PathRejection>,
    req: Result<Json<LightDto>, JsonRejection>,
) -> Answer {
    let name = name_of(name)?;
    let light = json_of(req)?;
    write(&h, Edit::PutLight { name, light }, StatusCode::OK).await
}

async fn delete_light(
    State(h): State<Handle>,
    name: Result<Path<String>, PathRejection>,
) -> Answer {
    let name = name_of(name)?;
    write(&h, Edit::DeleteLight { name }, StatusCode::OK).await
}
