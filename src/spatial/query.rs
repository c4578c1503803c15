//! The queries and their answers: what a client asks (a ball, a box, a point, a ray)
//! and what it gets back, all in world coordinates.

use glam::DVec3;
use serde::{Deserialize, Serialize};

/// How much of each body a sphere or box query answers with.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Detail {
    /// The bodies only: id, name, distance, inside.
    Bodies,
    /// The bodies with the faces that meet the region, the vertices inside it and the
    /// edges that enter it, clipped to it.
    #[default]
    Features,
    /// As `features`, with each face's portion inside the region as polygons.
    Portions,
}

impl Detail {
    /// The name used in requests.
    pub fn name(self) -> &'static str {
        match self {
            Detail::Bodies => "bodies",
            Detail::Features => "features",
            Detail::Portions => "portions",
        }
    }
}

/// The default chord tolerance of face portions, in meters (1 mm).
pub const DEFAULT_TOLERANCE: f64 = 1e-3;
/// The default largest number of faces, edges and vertices in one answer.
pub const DEFAULT_MAX_FEATURES: usize = 200_000;

/// A query refused before it ran.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum QueryError {
    /// A coordinate is NaN or infinite.
    #[error("{what} must be finite numbers")]
    NotFinite {
        /// Which input.
        what: &'static str,
    },
    /// The sphere's radius is negative.
    #[error("the radius must be zero or more (got {0})")]
    NegativeRadius(f64),
    /// The box's minimum exceeds its maximum on some axis.
    #[error("the box is empty: min must not exceed max on any axis")]
    EmptyBox,
    /// The ray's direction has no length.
    #[error("the ray's direction must not be zero")]
    ZeroDirection,
    /// The chord tolerance is not a positive length.
    #[error("the tolerance must be a positive length (got {0})")]
    BadTolerance(f64),
    /// The largest distance is negative.
    #[error("max_distance must be zero or more (got {0})")]
    NegativeDistance(f64),
    /// The answer would hold more bodies than allowed.
    #[error("the answer would hold more than {limit} bodies; ask for a smaller region")]
    TooManyBodies {
        /// The limit.
        limit: usize,
    },
    /// The answer would hold more features than allowed.
    #[error(
        "the answer would hold more than {limit} faces, edges and vertices; \
         ask for a smaller region or a lower detail"
    )]
    TooManyFeatures {
        /// The limit.
        limit: usize,
    },
}

fn finite(v: DVec3, what: &'static str) -> Result<(), QueryError> {
    if v.is_finite() {
        Ok(())
    } else {
        Err(QueryError::NotFinite { what })
    }
}

/// A sphere query: the portions of bodies within `radius` of `center`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SphereQuery {
    /// The centre (world).
    pub center: DVec3,
    /// The radius, ≥ 0.
    pub radius: f64,
    /// How much to answer.
    pub detail: Detail,
    /// The largest distance between a portion's chords and the circle they follow.
    pub tolerance: f64,
    /// The largest number of faces, edges and vertices in the answer.
    pub max_features: usize,
    /// The largest number of bodies in the answer (no limit by default).
    pub max_bodies: usize,
}

impl SphereQuery {
    /// A query at `features` detail with the default tolerance and limit.
    pub fn new(center: DVec3, radius: f64) -> SphereQuery {
        SphereQuery {
            center,
            radius,
            detail: Detail::Features,
            tolerance: DEFAULT_TOLERANCE,
            max_features: DEFAULT_MAX_FEATURES,
            max_bodies: usize::MAX,
        }
    }

    /// The same query at `detail`.
    pub fn with_detail(mut self, detail: Detail) -> SphereQuery {
        self.detail = detail;
        self
    }

    /// Refuses NaN or infinite coordinates, a negative or NaN radius and a tolerance
    /// that is not a positive length.
    pub fn validate(&self) -> Result<(), QueryError> {
        finite(self.center, "the centre's coordinates")?;
        if !self.radius.is_finite() {
            return Err(QueryError::NotFinite { what: "the radius" });
        }
        if self.radius < 0.0 {
            return Err(QueryError::NegativeRadius(self.radius));
        }
        if !(self.tolerance > 0.0 && self.tolerance.is_finite()) {
            return Err(QueryError::BadTolerance(self.tolerance));
        }
        Ok(())
    }
}

/// A box query: the portions of bodies inside the closed box `min..=max`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BoxQuery {
    /// Smallest corner (world).
    pub min: DVec3,
    /// Largest corner (world).
    pub max: DVec3,
    /// How much to answer.
    pub detail: Detail,
    /// The largest number of faces, edges and vertices in the answer.
    pub max_features: usize,
    /// The largest number of bodies in the answer (no limit by default).
    pub max_bodies: usize,
}

impl BoxQuery {
    /// A query at `features` detail with the default limit.
    pub fn new(min: DVec3, max: DVec3) -> BoxQuery {
        BoxQuery {
            min,
            max,
            detail: Detail::Features,
            max_features: DEFAULT_MAX_FEATURES,
            max_bodies: usize::MAX,
        }
    }

    /// Refuses NaN or infinite corners and an empty box (a flat box is allowed).
    pub fn validate(&self) -> Result<(), QueryError> {
        finite(self.min, "the box's min")?;
        finite(self.max, "the box's max")?;
        if self.min.cmpgt(self.max).any() {
            return Err(QueryError::EmptyBox);
        }
        Ok(())
    }
}

/// Checks a point and a largest distance (`INFINITY` for none).
pub fn validate_point(point: DVec3, max_distance: f64) -> Result<(), QueryError> {
    finite(point, "the point's coordinates")?;
    if max_distance.is_nan() {
        return Err(QueryError::NotFinite {
            what: "max_distance",
        });
    }
    if max_distance < 0.0 {
        return Err(QueryError::NegativeDistance(max_distance));
    }
    Ok(())
}

/// Checks a ray and answers its unit direction.
pub fn validate_ray(
    origin: DVec3,
    direction: DVec3,
    max_distance: f64,
) -> Result<DVec3, QueryError> {
    finite(origin, "the origin's coordinates")?;
    finite(direction, "the direction's coordinates")?;
    validate_point(origin, max_distance)?;
    let len = direction.length();
    if !len.is_finite() || len <= 0.0 {
        return Err(QueryError::ZeroDirection);
    }
    Ok(direction / len)
}

/// A body that reaches into the queried region.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct BodyHit {
    /// The body's id.
    pub id: u64,
    /// Its name, if it has one.
    pub name: Option<String>,
    /// Sphere queries: the distance from the centre to the solid (0 when inside).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub distance: Option<f64>,
    /// Whether the centre (of the sphere or box) is inside the solid (or on its surface).
    pub inside: bool,
    /// The faces that meet the region, by id (absent at `bodies` detail).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub faces: Option<Vec<FaceHit>>,
    /// The edges that enter the region, clipped to it.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub edges: Option<Vec<EdgeHit>>,
    /// The vertices inside the region.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub vertices: Option<Vec<VertexHit>>,
}

/// A face that meets the region.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct FaceHit {
    /// The face's id.
    pub id: u64,
    /// Sphere queries: the distance from the centre to the face.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub distance: Option<f64>,
    /// At `portions` detail: the loops bounding the part of the face inside the region
    /// (counter-clockwise seen from outside the body; usually one).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub portion: Option<Vec<Vec<DVec3>>>,
}

/// An edge that enters the region: the part of it inside.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct EdgeHit {
    /// The edge's id.
    pub id: u64,
    /// The clipped segment, from the NVT end towards the PVT end (both ends equal when
    /// the edge only touches the region).
    pub segment: [DVec3; 2],
}

/// A vertex inside the region.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct VertexHit {
    /// The vertex's id.
    pub id: u64,
    /// Its world locus.
    pub position: DVec3,
}

/// The answer to a sphere query.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct SphereAnswer {
    /// The world revision the answer was computed at.
    pub revision: u64,
    /// The centre asked about.
    pub center: DVec3,
    /// The radius asked about.
    pub radius: f64,
    /// The detail answered.
    pub detail: Detail,
    /// At `portions` detail: how far the portions' chords stray from the circles they
    /// follow at most.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub tolerance: Option<f64>,
    /// The bodies reaching into the sphere, nearest first (ties by id).
    pub bodies: Vec<BodyHit>,
}

/// The answer to a box query.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct BoxAnswer {
    /// The world revision the answer was computed at.
    pub revision: u64,
    /// The box asked about.
    pub min: DVec3,
    /// The box asked about.
    pub max: DVec3,
    /// The detail answered.
    pub detail: Detail,
    /// The bodies reaching into the box, by id.
    pub bodies: Vec<BodyHit>,
}

/// The body nearest a point.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Nearest {
    /// The body's id.
    pub id: u64,
    /// Its name.
    pub name: Option<String>,
    /// Distance from the point to the solid (0 inside).
    pub distance: f64,
    /// Whether the point is inside the solid (or on its surface).
    pub inside: bool,
    /// Distance from the point to the body's surface.
    pub surface_distance: f64,
    /// The closest point of the surface (world).
    pub point: DVec3,
    /// The face that point is on.
    pub face: u64,
}

/// The first surface a ray meets.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct RayHit {
    /// The body's id.
    pub id: u64,
    /// Its name.
    pub name: Option<String>,
    /// The face hit.
    pub face: u64,
    /// Where (world).
    pub point: DVec3,
    /// Distance along the ray.
    pub distance: f64,
    /// The face's outward unit normal (world).
    pub normal: DVec3,
    /// Whether the ray enters the solid there (meets the face from outside).
    pub entering: bool,
}

/// An answer about one point or ray, with the revision it was computed at.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Found<T> {
    /// The world revision.
    pub revision: u64,
    /// The hit, if any.
    pub hit: Option<T>,
}
