//! The model's routes: bodies, their topology and operators, cameras and lights.

use axum::Json;
use axum::extract::{Extension, State};
use axum::http::StatusCode;
use axum::http::header::ETAG;
use axum::response::IntoResponse;
use serde::Deserialize;

use super::extract::{ApiJson, ApiPath, ApiQuery};
use super::precondition::{IfMatch, Unused, WriteJson, etag};
use super::{Answer, HeavyReads, read_answer, snapshot, world_size, write};
use crate::edit::Edit;
use crate::model::{BodyId, Serial, World};
use crate::server::actor::Applied;
use crate::server::actor::Handle;
use crate::server::dto::{
    BodyAnswer, BodyDto, BodyList, BooleanAnswer, EdgeDto, FaceDto, TopologyDto, VertexDto,
    WorldSummary, euler_of,
};
use crate::server::problem::Problem;
use crate::server::request::{
    BooleanReq, CopyReq, CreateBody, EulerOp, HexColor, NewBody, PatchBody, SweepReq, TransformReq,
};

pub(super) async fn world(State(h): State<Handle>) -> Answer {
    let w = snapshot(&h).await?;
    let (f, e, v) = world_size(&w);
    Ok(read_answer(
        w.revision(),
        WorldSummary {
            revision: w.revision(),
            bodies: w.body_count(),
            faces: f,
            edges: e,
            vertices: v,
            cameras: w.camera_register().len(),
            lights: w.light_register().len(),
        },
    ))
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
        color: HexColor(node.color.unwrap_or_else(|| crate::model::default_color(b))),
        euler: euler_of(body),
        volume: body.volume(),
        area: body.surface_area(),
        bounds: body.bounds().map(Into::into),
        provisional: node.perceived.is_some(),
        views: node.perceived.as_ref().map(|p| p.views),
    })
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct ListQuery {
    name: Option<String>,
    parent: Option<u64>,
}

pub(super) async fn list_bodies(
    State(h): State<Handle>,
    ApiQuery(mut q): ApiQuery<ListQuery>,
) -> Answer {
    // A name is looked up in normalization form C, the form names are stored in; a name
    // no body can have even then is a mistake in the query, not an empty answer.
    if let Some(name) = q.name.as_mut() {
        use unicode_normalization::UnicodeNormalization;
        *name = name.nfc().collect();
        crate::model::parts::validate_name(name)
            .map_err(|reason| Problem::bad_request(format!("name {name:?}: {reason}")))?;
    }
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
    .map_err(Problem::internal)?;
    Ok(read_answer(revision, BodyList { bodies, revision }))
}

pub(super) async fn get_body(State(h): State<Handle>, ApiPath(id): ApiPath<u64>) -> Answer {
    let w = snapshot(&h).await?;
    let body = body_dto(&w, BodyId(Serial(id)))
        .ok_or_else(|| Problem::not_found(format!("no body has id {id}")))?;
    let revision = w.revision();
    Ok(read_answer(revision, BodyAnswer { body, revision }))
}

pub(super) async fn topology(
    State(h): State<Handle>,
    Extension(heavy): Extension<HeavyReads>,
    ApiPath(id): ApiPath<u64>,
) -> Answer {
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
    .map_err(Problem::internal)?
    .map_err(Problem::internal)?;
    Ok((
        [(axum::http::header::CONTENT_TYPE, "application/json")],
        bytes,
    )
        .into_response())
}

fn topology_dto(w: &World, b: BodyId) -> TopologyDto {
    let body = w.body(b).expect("checked by the caller");
    let perceived = w.perceived(b);
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
            made_by: perceived.and_then(|p| p.maker(body.face_serial(f))),
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

pub(super) async fn create_body(State(h): State<Handle>, req: WriteJson<CreateBody>) -> Answer {
    match NewBody::from(req.value) {
        NewBody::Solid(create) => {
            write(
                &h,
                Edit::CreateBody(create),
                req.expected,
                StatusCode::CREATED,
            )
            .await
        }
        NewBody::Mesh(mesh) => super::mesh::create(&h, mesh, req.expected).await,
    }
}

pub(super) async fn patch_body(
    State(h): State<Handle>,
    ApiPath(body): ApiPath<u64>,
    req: WriteJson<PatchBody>,
) -> Answer {
    let (patch, expected) = (req.value.into(), req.expected);
    write(
        &h,
        Edit::PatchBody { body, patch },
        expected,
        StatusCode::OK,
    )
    .await
}

pub(super) async fn delete_body(
    State(h): State<Handle>,
    IfMatch(expected): IfMatch,
    ApiPath(body): ApiPath<u64>,
    _unused: Unused,
) -> Answer {
    write(&h, Edit::DeleteBody { body }, expected, StatusCode::OK).await
}

pub(super) async fn euler(
    State(h): State<Handle>,
    ApiPath(body): ApiPath<u64>,
    req: WriteJson<EulerOp>,
) -> Answer {
    let (op, expected) = (req.value.into(), req.expected);
    write(&h, Edit::Euler { body, op }, expected, StatusCode::OK).await
}

pub(super) async fn transform(
    State(h): State<Handle>,
    ApiPath(body): ApiPath<u64>,
    req: WriteJson<TransformReq>,
) -> Answer {
    let (motion, expected) = (req.value.into(), req.expected);
    write(
        &h,
        Edit::Transform { body, motion },
        expected,
        StatusCode::OK,
    )
    .await
}

pub(super) async fn sweep(
    State(h): State<Handle>,
    ApiPath(body): ApiPath<u64>,
    req: WriteJson<SweepReq>,
) -> Answer {
    let (sweep, expected) = (req.value.into(), req.expected);
    write(&h, Edit::Sweep { body, sweep }, expected, StatusCode::OK).await
}

pub(super) async fn dual(
    State(h): State<Handle>,
    IfMatch(expected): IfMatch,
    ApiPath(body): ApiPath<u64>,
    _unused: Unused,
) -> Answer {
    write(&h, Edit::Dual { body }, expected, StatusCode::OK).await
}

pub(super) async fn evert(
    State(h): State<Handle>,
    IfMatch(expected): IfMatch,
    ApiPath(body): ApiPath<u64>,
    _unused: Unused,
) -> Answer {
    write(&h, Edit::Evert { body }, expected, StatusCode::OK).await
}

pub(super) async fn copy(
    State(h): State<Handle>,
    IfMatch(expected): IfMatch,
    ApiPath(body): ApiPath<u64>,
    req: Option<ApiJson<CopyReq>>,
) -> Answer {
    // The body is optional: none (no Content-Type) means an unnamed copy.
    let name = req.and_then(|ApiJson(r)| r.name);
    write(&h, Edit::Copy { body, name }, expected, StatusCode::CREATED).await
}

/// `POST /v1/bodies/{id}/boolean`: the body combined with another (BIN, BUN or the
/// difference); the result replaces it, and the answer lists the bodies left and killed.
pub(super) async fn boolean(
    State(h): State<Handle>,
    ApiPath(body): ApiPath<u64>,
    req: WriteJson<BooleanReq>,
) -> Answer {
    let (edit, expected) = (req.value.into_edit(body), req.expected);
    let Applied { outcome, revision } = h.apply_if(edit, expected).await?;
    let answer = BooleanAnswer::new(body, outcome, revision);
    Ok(([(ETAG, etag(revision))], Json(answer)).into_response())
}
