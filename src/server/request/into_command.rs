//! Requests into commands: each write request's JSON body becomes the edit language's
//! command it asks for. Defaults were filled when the request was read; nothing is
//! checked here (the command is checked when it is planned and applied).

use glam::{DVec2, DVec3};

use super::{
    BooleanOp, BooleanReq, CameraReq, CreateBody, EulerOp, FrameDto, LightDto, MeshShape,
    PatchBody, PoseDto, Shape, SweepKind, SweepReq, TransformOp, TransformReq,
};
use crate::edit::Edit;
use crate::edit::command::{self, CameraSpec, LightSpec, LookAt, Motion, Move, Raster, Sweep};
use crate::model::boolean::Op;
use crate::model::{Frame, Intrinsics, Pose};

fn v3(v: [f64; 3]) -> DVec3 {
    DVec3::from_array(v)
}

impl From<PoseDto> for Pose {
    fn from(p: PoseDto) -> Self {
        p.to_pose()
    }
}

/// What `POST /v1/bodies` asks for: a solid (one edit as it is), or a mesh file to read
/// first.
pub enum NewBody {
    /// A solid of the edit language.
    Solid(command::CreateBody),
    /// A mesh file, and where its bodies go.
    Mesh(MeshCreate),
}

/// A mesh file to read and where its bodies go.
pub struct MeshCreate {
    /// The file and how to read it.
    pub shape: MeshShape,
    /// The name of the file's first body.
    pub name: Option<String>,
    /// The supart of the file's top-level bodies.
    pub parent: Option<u64>,
    /// Composed before each top-level body's pose from the file.
    pub pose: Option<Pose>,
    /// The colour of every body, over the file's.
    pub color: Option<crate::model::Color>,
}

impl From<CreateBody> for NewBody {
    fn from(req: CreateBody) -> Self {
        let pose = req.pose.map(Pose::from);
        let color = req.color.map(|c| c.0);
        match command_shape(req.shape) {
            Ok(shape) => NewBody::Solid(command::CreateBody {
                name: req.name,
                parent: req.parent,
                pose,
                color,
                shape,
            }),
            Err(mesh) => NewBody::Mesh(MeshCreate {
                shape: *mesh,
                name: req.name,
                parent: req.parent,
                pose,
                color,
            }),
        }
    }
}

/// The edit language's shape for a solid, or the mesh shape, which has none.
fn command_shape(shape: Shape) -> Result<command::Shape, Box<MeshShape>> {
    let points = |p: Vec<[f64; 2]>| p.into_iter().map(DVec2::from_array).collect();
    Ok(match shape {
        Shape::Box { size } => command::Shape::Box { size: v3(size) },
        Shape::Tetrahedron { radius } => command::Shape::Tetrahedron { radius },
        Shape::Prism { polygon, height } => command::Shape::Prism {
            polygon: points(polygon),
            height,
        },
        Shape::Pyramid { polygon, height } => command::Shape::Pyramid {
            polygon: points(polygon),
            height,
        },
        Shape::Cylinder {
            radius,
            height,
            segments,
        } => command::Shape::Cylinder {
            radius,
            height,
            segments,
        },
        Shape::Cone {
            radius,
            height,
            segments,
        } => command::Shape::Cone {
            radius,
            height,
            segments,
        },
        Shape::Sphere {
            radius,
            segments,
            rings,
        } => command::Shape::Sphere {
            radius,
            segments,
            rings,
        },
        Shape::Torus {
            major_radius,
            minor_radius,
            segments,
            rings,
        } => command::Shape::Torus {
            major_radius,
            minor_radius,
            segments,
            rings,
        },
        Shape::Polyhedron { vertices, faces } => command::Shape::Polyhedron {
            vertices: vertices.into_iter().map(v3).collect(),
            faces,
        },
        Shape::Seminal { position } => command::Shape::Seminal {
            position: v3(position),
        },
        Shape::Mesh(mesh) => return Err(mesh),
    })
}

impl From<PatchBody> for command::PatchBody {
    fn from(req: PatchBody) -> Self {
        command::PatchBody {
            name: req.name,
            parent: req.parent,
            pose: req.pose.map(Pose::from),
            color: req.color.map(|c| c.map(|c| c.0)),
        }
    }
}

impl From<EulerOp> for command::EulerOp {
    fn from(op: EulerOp) -> Self {
        use command::EulerOp as C;
        match op {
            EulerOp::Mkev {
                face,
                vertex,
                position,
            } => C::Mkev {
                face,
                vertex,
                position: position.map(v3),
            },
            EulerOp::Mkfe { v1, face, v2 } => C::Mkfe { v1, face, v2 },
            EulerOp::Esplit { edge, position } => C::Esplit {
                edge,
                position: position.map(v3),
            },
            EulerOp::Klfe { edge } => C::Klfe { edge },
            EulerOp::Klev { vertex } => C::Klev { vertex },
            EulerOp::Klve { edge } => C::Klve { edge },
            EulerOp::Invert { edge } => C::Invert { edge },
            EulerOp::Glue {
                face1,
                face2,
                vertex1,
                vertex2,
            } => C::Glue {
                face1,
                face2,
                vertex1,
                vertex2,
            },
            EulerOp::Gluee {
                face1,
                vertex1,
                face2,
                vertex2,
            } => C::Gluee {
                face1,
                vertex1,
                face2,
                vertex2,
            },
            EulerOp::Glueff { face1, face2 } => C::Glueff { face1, face2 },
            EulerOp::Unglue { edges } => C::Unglue { edges },
        }
    }
}

impl From<TransformReq> for Move {
    fn from(req: TransformReq) -> Self {
        let motion = match req.op {
            TransformOp::Translate { vector } => Motion::Translate { vector: v3(vector) },
            TransformOp::Rotate {
                axis,
                angle_deg,
                center,
            } => Motion::Rotate {
                axis: v3(axis),
                angle_deg,
                center: v3(center),
            },
            TransformOp::Dilate { factor, center } => Motion::Dilate {
                factor,
                center: v3(center),
            },
            TransformOp::Reflect { normal, point } => Motion::Reflect {
                normal: v3(normal),
                point: v3(point),
            },
        };
        Move {
            motion,
            frame: match req.frame {
                FrameDto::World => Frame::World,
                FrameDto::Body => Frame::Body,
            },
            target: req.target,
        }
    }
}

impl From<SweepReq> for Sweep {
    fn from(req: SweepReq) -> Self {
        Sweep {
            face: req.face,
            kind: match req.kind {
                SweepKind::Prism => command::SweepKind::Prism,
                SweepKind::Pyramid => command::SweepKind::Pyramid,
                SweepKind::CwPrismoid => command::SweepKind::CwPrismoid,
                SweepKind::CcwPrismoid => command::SweepKind::CcwPrismoid,
            },
            distance: req.distance,
            offset: req.offset.map(v3),
            peak: req.peak.map(v3),
            scale: req.scale,
        }
    }
}

impl From<BooleanOp> for Op {
    fn from(op: BooleanOp) -> Self {
        match op {
            BooleanOp::Intersection => Op::Intersection,
            BooleanOp::Union => Op::Union,
            BooleanOp::Difference => Op::Difference,
        }
    }
}

impl BooleanReq {
    /// The edit this request asks of body `body` (B1).
    pub fn into_edit(self, body: u64) -> Edit {
        Edit::Boolean {
            body,
            with: self.with,
            op: self.op.into(),
            keep_with: self.keep_with,
        }
    }
}

impl From<CameraReq> for CameraSpec {
    fn from(req: CameraReq) -> Self {
        CameraSpec {
            pose: req.pose.map(Pose::from),
            look_at: req.look_at.map(|l| LookAt {
                eye: v3(l.eye),
                target: v3(l.target),
                up: v3(l.up),
            }),
            intrinsics: req.intrinsics.map(|i| Intrinsics {
                width: i.width,
                height: i.height,
                fx: i.fx,
                fy: i.fy,
                cx: i.cx,
                cy: i.cy,
            }),
            baumgart: req.baumgart.map(|b| Raster {
                focal: b.focal,
                ldx: b.ldx,
                ldy: b.ldy,
                pdx: b.pdx,
                pdy: b.pdy,
            }),
        }
    }
}

impl From<LightDto> for LightSpec {
    fn from(req: LightDto) -> Self {
        match req {
            LightDto::Sun {
                direction,
                intensity,
            } => LightSpec::Sun {
                direction: v3(direction),
                intensity,
            },
            LightDto::Point {
                position,
                intensity,
            } => LightSpec::Point {
                position: v3(position),
                intensity,
            },
        }
    }
}
