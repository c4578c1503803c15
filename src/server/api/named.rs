//! Cameras and lights over HTTP: one set of handlers (list, get, put, delete) serves
//! every kind of thing the world keeps by name, each kind described by a [`Resource`].

use axum::extract::State;
use axum::http::StatusCode;
use serde::Serialize;
use serde::de::DeserializeOwned;
use serde::ser::SerializeMap;

use super::extract::ApiPath;
use super::precondition::{IfMatch, Unused, WriteJson};
use super::{Answer, read_answer, snapshot, write};
use crate::edit::Edit;
use crate::model::camera::{Camera, Light};
use crate::model::{Named, Register, World};
use crate::server::actor::Handle;
use crate::server::dto::{CameraDto, LightAnswer};
use crate::server::problem::Problem;
use crate::server::request::{CameraReq, LightDto};

/// A kind of thing kept by name, as the HTTP API shows it.
pub(super) trait Resource: Named + Sized + 'static {
    /// Its name, for messages ("camera").
    const KIND: &'static str;
    /// Its name in the plural, the key of a listing ("cameras").
    const PLURAL: &'static str;
    /// The body of a `PUT`.
    type Request: DeserializeOwned + Send + 'static;
    /// The answer for one thing.
    type Answer: Serialize;
    /// The world's things of this kind.
    fn register(world: &World) -> &Register<Self>;
    /// The answer for `thing`, named `name`.
    fn answer(name: &str, thing: &Self) -> Self::Answer;
    /// The edit that stores `request` as `name`.
    fn put(name: String, request: Self::Request) -> Edit;
    /// The edit that removes `name`.
    fn delete(name: String) -> Edit;
}

impl Resource for Camera {
    const KIND: &'static str = "camera";
    const PLURAL: &'static str = "cameras";
    type Request = CameraReq;
    type Answer = CameraDto;
    fn register(world: &World) -> &Register<Self> {
        world.camera_register()
    }
    fn answer(name: &str, camera: &Self) -> CameraDto {
        CameraDto::new(name, camera)
    }
    fn put(name: String, request: CameraReq) -> Edit {
        Edit::PutCamera {
            name,
            camera: request.into(),
        }
    }
    fn delete(name: String) -> Edit {
        Edit::DeleteCamera { name }
    }
}

impl Resource for Light {
    const KIND: &'static str = "light";
    const PLURAL: &'static str = "lights";
    type Request = LightDto;
    type Answer = LightAnswer;
    fn register(world: &World) -> &Register<Self> {
        world.light_register()
    }
    fn answer(name: &str, light: &Self) -> LightAnswer {
        LightAnswer::new(name, light)
    }
    fn put(name: String, request: LightDto) -> Edit {
        Edit::PutLight {
            name,
            light: request.into(),
        }
    }
    fn delete(name: String) -> Edit {
        Edit::DeleteLight { name }
    }
}

/// A listing: `{"<plural>": [...], "revision": n}`.
struct Listing<T> {
    key: &'static str,
    items: Vec<T>,
    revision: u64,
}

impl<T: Serialize> Serialize for Listing<T> {
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        let mut map = s.serialize_map(Some(2))?;
        map.serialize_entry(self.key, &self.items)?;
        map.serialize_entry("revision", &self.revision)?;
        map.end()
    }
}

/// `GET /v1/cameras`, `GET /v1/lights`: every one, in name order.
pub(super) async fn list<R: Resource>(State(h): State<Handle>) -> Answer {
    let w = snapshot(&h).await?;
    let listing = Listing {
        key: R::PLURAL,
        items: R::register(&w)
            .iter()
            .map(|(name, thing)| R::answer(name, thing))
            .collect(),
        revision: w.revision(),
    };
    Ok(read_answer(w.revision(), listing))
}

/// `GET /v1/cameras/{name}`, `GET /v1/lights/{name}`.
pub(super) async fn get_one<R: Resource>(
    State(h): State<Handle>,
    ApiPath(name): ApiPath<String>,
) -> Answer {
    let w = snapshot(&h).await?;
    let thing = R::register(&w)
        .get(&name)
        .ok_or_else(|| Problem::not_found(format!("no {} is named {:?}", R::KIND, name)))?;
    Ok(read_answer(w.revision(), R::answer(&name, thing)))
}

/// `PUT /v1/cameras/{name}`, `PUT /v1/lights/{name}`: store or replace.
pub(super) async fn put<R: Resource>(
    State(h): State<Handle>,
    ApiPath(name): ApiPath<String>,
    req: WriteJson<R::Request>,
) -> Answer {
    write(&h, R::put(name, req.value), req.expected, StatusCode::OK).await
}

/// `DELETE /v1/cameras/{name}`, `DELETE /v1/lights/{name}`.
pub(super) async fn delete<R: Resource>(
    State(h): State<Handle>,
    IfMatch(expected): IfMatch,
    ApiPath(name): ApiPath<String>,
    _unused: Unused,
) -> Answer {
    write(&h, R::delete(name), expected, StatusCode::OK).await
}
