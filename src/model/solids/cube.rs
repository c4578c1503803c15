//! MKCUBE: the rectangular box built through the Euler operators, as in the seeds.

use glam::DVec3;

use crate::model::body::Body;
use crate::model::euler::EulerError;
use crate::model::ids::Serials;

/// MKCUBE(DX, DY, DZ): a box of the given size centred on the origin, made as GEOMED's
/// example 3 makes it: MKBFV, three MKEVs to a wire, MKFE to a lamina, four spurs, four
/// MKFEs. F = 6, E = 12, V = 8. `mkcube(serials, 2, 2, 2)` spans −1..1 on every axis.
///
/// Precondition: finite positive sizes (the caller checks; the topology is right for any
/// sizes, the orientation only for positive ones).
pub fn mkcube(serials: &mut Serials, dx: f64, dy: f64, dz: f64) -> Result<Body, EulerError> {
    let (x, y, z) = (dx / 2.0, dy / 2.0, dz / 2.0);
    let (mut b, f, v1) = Body::seminal(serials, DVec3::new(x, y, -z));
    // Make the rectangular lamina.
    let (_, v2) = b.mkev(serials, f, v1, DVec3::new(-x, y, -z))?;
    let (_, v3) = b.mkev(serials, f, v2, DVec3::new(-x, -y, -z))?;
    let (_, v4) = b.mkev(serials, f, v3, DVec3::new(x, -y, -z))?;
    let (_, top) = b.mkfe(serials, v1, f, v4)?;
    // Four spurs up from the lamina's top face.
    let mut tips = [v1; 4];
    for (tip, v) in tips.iter_mut().zip([v1, v2, v3, v4]) {
        let p = b.position(v);
        *tip = b.mkev(serials, top, v, DVec3::new(p.x, p.y, z))?.1;
    }
    // Tie the spurs together to form the four sides; `top` ends as the top face.
    for i in 0..4 {
        b.mkfe(serials, tips[i], top, tips[(i + 1) % 4])?;
    }
    Ok(b)
}
