use glam::{DAffine3, DQuat, DVec3};
use winged::model::boolean::{Op, Operand, Solution, boolean};
use winged::model::check::{Violation, check_solid};
use winged::model::solids::{box_solid, cylinder, sphere};
use winged::model::{Body, Serials};

struct Rng(u64);
impl Rng {
    fn next(&mut self) -> u64 {
        self.0 ^= self.0 << 13;
        self.0 ^= self.0 >> 7;
        self.0 ^= self.0 << 17;
        self.0
    }
    fn int(&mut self, n: u64) -> i64 {
        (self.next() % n) as i64
    }
    fn f(&mut self) -> f64 {
        (self.next() >> 11) as f64 / (1u64 << 53) as f64
    }
}

fn vol(sol: &Solution) -> Result<f64, String> {
    let mut s = Serials::new();
    let mut v = 0.0;
    for sh in &sol.shells {
        let b = Body::from_polygons(&mut s, &sh.positions, &sh.faces)
            .map_err(|e| format!("build: {e}"))?;
        let r = check_solid(&b, 1e-9);
        if !r
            .violations
            .iter()
            .all(|v| matches!(v, Violation::Inward { .. }))
        {
            return Err(format!("check: {r}"));
        }
        v += b.volume();
    }
    Ok(v)
}

fn main() {
    let n: usize = std::env::args()
        .nth(1)
        .and_then(|a| a.parse().ok())
        .unwrap_or(1000);
    let kind: u64 = std::env::args()
        .nth(2)
        .and_then(|a| a.parse().ok())
        .unwrap_or(0);
    let mut rng = Rng(0x9e3779b97f4a7c15);
    let mut s = Serials::new();
    let (mut fails, mut worst) = (0, 0.0f64);
    let t0 = std::time::Instant::now();
    for case in 0..n {
        let size = |r: &mut Rng| {
            DVec3::new(
                1.0 + r.int(3) as f64,
                1.0 + r.int(3) as f64,
                1.0 + r.int(3) as f64,
            )
        };
        let (a, b, pa, pb);
        match kind {
            0 => {
                a = box_solid(&mut s, size(&mut rng)).unwrap();
                b = box_solid(&mut s, size(&mut rng)).unwrap();
                pa = DAffine3::from_translation(DVec3::new(
                    rng.int(4) as f64 * 0.5,
                    rng.int(4) as f64 * 0.5,
                    rng.int(4) as f64 * 0.5,
                ));
                pb = DAffine3::from_translation(DVec3::new(
                    rng.int(4) as f64 * 0.5,
                    rng.int(4) as f64 * 0.5,
                    rng.int(4) as f64 * 0.5,
                ));
            }
            1 => {
                a = box_solid(&mut s, size(&mut rng)).unwrap();
                b = box_solid(&mut s, size(&mut rng)).unwrap();
                let angles = [0.0, 1e-12, 1e-9, 1e-6, rng.f()];
                let ang = angles[rng.int(5) as usize].to_radians();
                pa = DAffine3::IDENTITY;
                pb = DAffine3::from_rotation_translation(
                    DQuat::from_rotation_z(ang) * DQuat::from_rotation_x(ang * 0.7),
                    DVec3::new(
                        rng.int(3) as f64 * 0.5,
                        rng.int(3) as f64 * 0.5,
                        if rng.int(2) == 0 { 0.0 } else { 1e-12 },
                    ),
                );
            }
            _ => {
                a = sphere(
                    &mut s,
                    1.0,
                    12 + rng.int(8) as usize,
                    6 + rng.int(5) as usize,
                )
                .unwrap();
                b = cylinder(&mut s, 0.5, 3.0, 5 + rng.int(10) as usize).unwrap();
                pa = DAffine3::IDENTITY;
                pb = DAffine3::from_rotation_translation(
                    DQuat::from_rotation_y(rng.f() * 3.0),
                    DVec3::new(rng.f() - 0.5, rng.f() - 0.5, 0.0),
                );
            }
        }
        let only: Option<usize> = std::env::var("CASE").ok().and_then(|c| c.parse().ok());
        if only.is_some_and(|c| c != case) {
            continue;
        }
        if only.is_some() {
            println!(
                "A {:?} at {:?}\nB {:?} at {:?}",
                a.bounds(),
                pa.translation,
                b.bounds(),
                pb.translation
            );
        }
        let oa = Operand {
            body: &a,
            place: pa,
        };
        let ob = Operand {
            body: &b,
            place: pb,
        };
        let r = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| {
            let i = boolean(oa, ob, Op::Intersection).map_err(|e| format!("i: {e}"))?;
            let u = boolean(oa, ob, Op::Union).map_err(|e| format!("u: {e}"))?;
            if only.is_some() {
                for sh in &u.shells {
                    println!("{:?}\n{:?}", sh.positions, sh.faces);
                }
            }
            let d = boolean(oa, ob, Op::Difference).map_err(|e| format!("d: {e}"))?;
            let (vi, vu, vd) = (
                vol(&i).map_err(|e| format!("i {e}"))?,
                vol(&u).map_err(|e| format!("u {e}"))?,
                vol(&d).map_err(|e| format!("d {e}"))?,
            );
            let (va, vb) = (a.volume(), b.volume());
            let e1 = (va + vb - vu - vi).abs();
            let e2 = (vd - (va - vi)).abs();
            Ok::<f64, String>(e1.max(e2) / va.max(vb).max(vu))
        }));
        match r {
            Ok(Ok(e)) => {
                worst = worst.max(e);
                if e > 1e-12 {
                    fails += 1;
                    if fails < 5 {
                        println!("case {case}: identity off by {e:e}");
                    }
                }
            }
            Ok(Err(msg)) => {
                fails += 1;
                if fails < 8 {
                    println!("case {case}: {msg}");
                }
            }
            Err(_) => {
                fails += 1;
                println!("case {case}: panic");
            }
        }
    }
    println!(
        "{n} cases kind {kind}: {fails} failures, worst identity {worst:e}, {:?}",
        t0.elapsed()
    );
}
