//! Baumgart's geometric primitives TRANSLATE, ROTATE, DILATE and REFLECT: the Euclidean
//! transformations (with dilation, the similarity group of Klein's Erlangen programme),
//! applied to the vertex loci of a body, a face, an edge or a vertex.
//!
//! "A body is the set of vertices in its vertex ring, a face is the set of vertices on
//! its perimeter, an edge is the two vertices which are its ends, and a single vertex is
//! itself." A transform changes only loci, never topology, with one exception: REFLECT of
//! a whole body also EVERTs it (see [`Transform::plan`]).
//!
//! Loci are stored in the body's own frame. A transform may be given in that frame
//! ([`Frame::Body`], Baumgart's "negative body argument") or in world coordinates
//! ([`Frame::World`]); a world-frame transform `T` is conjugated by the body's world pose
//! `P` and applied to the loci as `P⁻¹ · T · P`, which moves the vertices' world loci by
//! exactly `T`.
//!
//! This module works on one [`Body`] and knows nothing of the parts tree; at world level
//! ([`World::transform`](super::World::transform)) a translation or rotation of a whole
//! body changes its pose instead, so that its sub-parts follow.
//!
//! Every operation checks all its inputs before changing anything ([`Transform::plan`]
//! can fail and changes nothing, [`Moves::apply`] cannot fail), so a refused transform
//! leaves the body exactly as it was.

use glam::{DAffine3, DMat3, DQuat, DVec3};

use super::body::Body;
use super::ids::{EdgeId, FaceId, VertexId};
use super::parts::Entity;
use super::pose::Pose;
use super::range::{self, MAX_COORDINATE, MIN_LENGTH, RangeError};

/// One of Baumgart's four Euclidean primitives, with its parameters (meters, radians).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Transform {
    /// TRANSLATE: `x ↦ x + by`. Inverse: `Translate(-by)`.
    Translate(DVec3),
    /// ROTATE: by `angle_rad` about the line through `center` along `axis`,
    /// counter-clockwise looking down the axis toward `center` (right-hand rule).
    /// Inverse: the same with `-angle_rad`.
    Rotate {
        /// The axis direction (any nonzero length).
        axis: DVec3,
        /// The angle, radians.
        angle_rad: f64,
        /// A point on the axis.
        center: DVec3,
    },
    /// DILATE: `x ↦ center + factor · (x − center)`, `factor > 0`. Inverse: the same with
    /// `1 / factor`. Volumes scale by `factor³`, areas by `factor²`.
    Dilate {
        /// The scale factor, positive.
        factor: f64,
        /// The fixed point.
        center: DVec3,
    },
    /// REFLECT: in the plane through `point` with normal `normal`. Its own inverse.
    /// Reverses orientation (see [`Transform::plan`] for how a body stays outward-facing).
    Reflect {
        /// The mirror plane's normal (any nonzero length).
        normal: DVec3,
        /// A point on the mirror plane.
        point: DVec3,
    },
}

/// The frame a transform's vectors and points are given in.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Default)]
pub enum Frame {
    /// World coordinates (Baumgart's default).
    #[default]
    World,
    /// The body's own coordinates, the frame its loci are stored in (Baumgart's negative
    /// body argument: `ROTATE(-J1, ...)` turns a joint about its own axes).
    Body,
}

/// Why a transform was refused. Nothing was changed.
#[derive(Debug, Clone, Copy, PartialEq, thiserror::Error)]
pub enum TransformError {
    /// A parameter is NaN or infinite.
    #[error("the transform's {what} is not finite")]
    NonFinite {
        /// Which parameter ("translation", "axis", "angle", "center", "factor",
        /// "normal", "point", or "body pose").
        what: &'static str,
    },
    /// A rotation axis of zero length.
    #[error("the rotation axis has zero length")]
    ZeroAxis,
    /// A mirror normal of zero length.
    #[error("the mirror normal has zero length")]
    ZeroNormal,
    /// A dilation factor that is not positive.
    #[error("the dilation factor {factor} is not positive")]
    BadFactor {
        /// The factor given.
        factor: f64,
    },
    /// A face that is not live in the body.
    #[error("face {0:?} is not a live face of this body")]
    UnknownFace(FaceId),
    /// An edge that is not live in the body.
    #[error("edge {0:?} is not a live edge of this body")]
    UnknownEdge(EdgeId),
    /// A vertex that is not live in the body.
    #[error("vertex {0:?} is not a live vertex of this body")]
    UnknownVertex(VertexId),
    /// Some transformed locus would overflow to infinity.
    #[error("the transformed loci would not be finite")]
    NonFiniteResult,
    /// Some transformed locus would leave the world's range, or a dilation would shrink
    /// what it moves below the smallest length (see [`crate::model::range`]).
    #[error("the transformed loci would leave the world's range: {0}")]
    OutOfRange(RangeError),
}

impl TransformError {
    /// Whether the refusal is about the world's range (see [`crate::model::range`]).
    pub fn is_out_of_range(&self) -> bool {
        matches!(self, TransformError::OutOfRange(_))
    }
}

fn finite(v: DVec3, what: &'static str) -> Result<(), TransformError> {
    if v.is_finite() {
        Ok(())
    } else {
        Err(TransformError::NonFinite { what })
    }
}

fn finite_scalar(x: f64, what: &'static str) -> Result<(), TransformError> {
    if x.is_finite() {
        Ok(())
    } else {
        Err(TransformError::NonFinite { what })
    }
}

/// The unit vector along `v`, whatever its magnitude (see [`range::unit`]).
fn unit(v: DVec3, what: &'static str, zero: TransformError) -> Result<DVec3, TransformError> {
    finite(v, what)?;
    range::unit(what, v).map_err(|_| zero)
}

impl Transform {
    /// Checks the parameters: all finite, axis and normal nonzero, factor positive.
    pub fn validate(&self) -> Result<(), TransformError> {
        self.to_affine().map(|_| ())
    }

    /// The transform as an affine map, in the frame its parameters are given in.
    /// Refused as [`Transform::validate`] refuses.
    pub fn to_affine(&self) -> Result<DAffine3, TransformError> {
        match *self {
            Transform::Translate(by) => {
                finite(by, "translation")?;
                Ok(DAffine3::from_translation(by))
            }
            Transform::Rotate {
                axis,
                angle_rad,
                center,
            } => {
                let axis = unit(axis, "axis", TransformError::ZeroAxis)?;
                finite_scalar(angle_rad, "angle")?;
                finite(center, "center")?;
                let q = DQuat::from_axis_angle(axis, angle_rad % std::f64::consts::TAU);
                Ok(DAffine3::from_rotation_translation(q, center - q * center))
            }
            Transform::Dilate { factor, center } => {
                finite_scalar(factor, "factor")?;
                if factor <= 0.0 {
                    return Err(TransformError::BadFactor { factor });
                }
                finite(center, "center")?;
                Ok(DAffine3::from_mat3_translation(
                    DMat3::from_diagonal(DVec3::splat(factor)),
                    (1.0 - factor) * center,
                ))
            }
            Transform::Reflect { normal, point } => {
                let n = unit(normal, "normal", TransformError::ZeroNormal)?;
                finite(point, "point")?;
                let m = DMat3::IDENTITY - 2.0 * DMat3::from_cols(n * n.x, n * n.y, n * n.z);
                Ok(DAffine3::from_mat3_translation(m, 2.0 * n.dot(point) * n))
            }
        }
    }

    /// The inverse transform: `t.inverse()` undoes `t`. Precondition: `t` is valid.
    pub fn inverse(&self) -> Transform {
        match *self {
            Transform::Translate(by) => Transform::Translate(-by),
            Transform::Rotate {
                axis,
                angle_rad,
                center,
            } => Transform::Rotate {
                axis,
                angle_rad: -angle_rad,
                center,
            },
            Transform::Dilate { factor, center } => Transform::Dilate {
                factor: 1.0 / factor,
                center,
            },
            r @ Transform::Reflect { .. } => r,
        }
    }

    /// Whether this is a rigid motion (TRANSLATE or ROTATE), which a pose can express.
    pub fn is_rigid(&self) -> bool {
        matches!(self, Transform::Translate(_) | Transform::Rotate { .. })
    }

    /// Whether this reverses orientation (REFLECT).
    pub fn reverses_orientation(&self) -> bool {
        matches!(self, Transform::Reflect { .. })
    }

    /// A rigid transform as a pose (the map `x ↦ rotation · x + position`); `None` for
    /// DILATE and REFLECT. Refused as [`Transform::validate`] refuses.
    pub fn to_pose(&self) -> Result<Option<Pose>, TransformError> {
        match *self {
            Transform::Translate(by) => {
                finite(by, "translation")?;
                Ok(Some(Pose::from_translation(by)))
            }
            Transform::Rotate {
                axis,
                angle_rad,
                center,
            } => {
                let axis = unit(axis, "axis", TransformError::ZeroAxis)?;
                finite_scalar(angle_rad, "angle")?;
                finite(center, "center")?;
                let q = DQuat::from_axis_angle(axis, angle_rad % std::f64::consts::TAU);
                Ok(Some(Pose {
                    position: center - q * center,
                    rotation: q,
                }))
            }
            _ => self.validate().map(|_| None),
        }
    }

    /// The affine map to apply to loci stored in a body frame whose world pose is
    /// `body_pose`: the transform itself for [`Frame::Body`], and
    /// `body_pose⁻¹ · T · body_pose` for [`Frame::World`].
    pub fn in_body_frame(
        &self,
        frame: Frame,
        body_pose: &Pose,
    ) -> Result<DAffine3, TransformError> {
        let m = self.to_affine()?;
        match frame {
            Frame::Body => Ok(m),
            Frame::World => {
                if !body_pose.is_finite() {
                    return Err(TransformError::NonFinite { what: "body pose" });
                }
                Ok(body_pose.inverse().to_affine() * m * body_pose.to_affine())
            }
        }
    }

    /// Plans the transform of `target` in `body` without changing anything: checks the
    /// parameters and the target, and computes every new locus.
    ///
    /// * `target` is [`Entity::Body`] (every vertex), a face (the distinct vertices on
    ///   its perimeter; none for a seminal face), an edge (its two ends) or a vertex.
    /// * `body_pose` is the body's world pose, used only for [`Frame::World`].
    ///
    /// Postcondition of applying the plan: each vertex of the target is moved by the
    /// transform (in world coordinates when `frame` is `World`); topology is unchanged,
    /// except that REFLECT of a whole body also EVERTs it: a mirror image reverses every
    /// face's sense of rotation, so without the evert the faces would run clockwise seen
    /// from outside and the volume would come out negative. With it the reflected body
    /// is again a closed, outward-facing solid with the same volume. REFLECT of a face,
    /// edge or vertex moves only those loci and does not evert anything.
    ///
    /// Moving only some vertices (a face, edge or vertex) may leave neighbouring faces
    /// non-planar or the surface self-intersecting, exactly as in Baumgart's GEOMED; the
    /// caller decides whether that is wanted (`check_solid` reports it).
    ///
    /// Refused ([`TransformError`]) when a parameter is not finite, an axis or normal is
    /// zero, a factor is not positive, the target is not live in `body`, a new locus
    /// would not be finite or would leave the world's range, or a DILATE would shrink
    /// the target's extent (the largest side of its loci's bounding box) below
    /// [`MIN_LENGTH`] (see [`crate::model::range`]).
    pub fn plan(
        &self,
        body: &Body,
        target: Entity,
        frame: Frame,
        body_pose: &Pose,
    ) -> Result<Moves, TransformError> {
        let m = self.in_body_frame(frame, body_pose)?;
        let mut vs: Vec<VertexId> = match target {
            Entity::Body => body.vertices().collect(),
            Entity::Face(f) => {
                if !body.has_face(f) {
                    return Err(TransformError::UnknownFace(f));
                }
                body.face_vertices(f).collect()
            }
            Entity::Edge(e) => {
                if !body.has_edge(e) {
                    return Err(TransformError::UnknownEdge(e));
                }
                body.edge(e).vt.to_vec()
            }
            Entity::Vertex(v) => {
                if !body.has_vertex(v) {
                    return Err(TransformError::UnknownVertex(v));
                }
                vec![v]
            }
        };
        vs.sort_unstable();
        vs.dedup();
        let moves: Vec<(VertexId, DVec3)> = vs
            .into_iter()
            .map(|v| (v, m.transform_point3(body.position(v))))
            .collect();
        if moves.iter().any(|(_, p)| !p.is_finite()) {
            return Err(TransformError::NonFiniteResult);
        }
        if let Some(&(_, p)) = moves
            .iter()
            .find(|(_, p)| !range::is_within(*p, MAX_COORDINATE))
        {
            return Err(TransformError::OutOfRange(
                range::coordinate("a transformed locus", p)
                    .expect_err("the locus is beyond the range"),
            ));
        }
        if let Transform::Dilate { factor, .. } = *self
            && factor < 1.0
        {
            let before = extent(moves.iter().map(|&(v, _)| body.position(v)));
            let after = extent(moves.iter().map(|&(_, p)| p));
            if after < MIN_LENGTH && after < before {
                return Err(TransformError::OutOfRange(RangeError::TooSmall {
                    what: "the dilated extent",
                    value: after,
                }));
            }
        }
        Ok(Moves {
            moves,
            evert: target == Entity::Body && self.reverses_orientation(),
        })
    }

    /// [`Transform::plan`] and then [`Moves::apply`]: transforms `target` in `body`, or
    /// refuses and leaves `body` unchanged.
    ///
    /// Inverse: applying [`Transform::inverse`] to the same target in the same frame
    /// (with the same body pose) restores the loci, up to rounding, and for REFLECT of a
    /// whole body everts it back.
    pub fn apply(
        &self,
        body: &mut Body,
        target: Entity,
        frame: Frame,
        body_pose: &Pose,
    ) -> Result<(), TransformError> {
        self.plan(body, target, frame, body_pose)?.apply(body);
        Ok(())
    }
}

/// The largest side of the bounding box of `points` (0 for none).
fn extent(points: impl Iterator<Item = DVec3>) -> f64 {
    let mut lo = DVec3::splat(f64::INFINITY);
    let mut hi = DVec3::splat(f64::NEG_INFINITY);
    for p in points {
        lo = lo.min(p);
        hi = hi.max(p);
    }
    if lo.x > hi.x {
        0.0
    } else {
        (hi - lo).max_element()
    }
}

/// The checked result of [`Transform::plan`]: new loci for some vertices, and whether the
/// body is to be everted.
#[derive(Clone, Debug, PartialEq)]
pub struct Moves {
    moves: Vec<(VertexId, DVec3)>,
    evert: bool,
}

impl Moves {
    /// The vertices to move and their new loci (body frame).
    pub fn moves(&self) -> &[(VertexId, DVec3)] {
        &self.moves
    }

    /// Whether applying also EVERTs the body (REFLECT of a whole body).
    pub fn everts(&self) -> bool {
        self.evert
    }

    /// Writes the new loci (and everts if planned). Cannot fail. Precondition: `body` is
    /// the body the plan was made for, unchanged since.
    pub fn apply(self, body: &mut Body) {
        for (v, p) in self.moves {
            body.set_position(v, p);
        }
        if self.evert {
            body.evert();
        }
    }
}
