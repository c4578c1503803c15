//! Spatial access side by side, in one process on the same data: winged's `Spatial`,
//! rstar's `RTree` (bulk-loaded rectangles) and parry3d's `Bvh` (axis-aligned boxes).
//!
//! ```text
//! bash bench/spatial/run.sh            # both data sets, then a table
//! bash bench/spatial/run.sh terrain    # one data set (terrain or city)
//! target/release/spatial-peers profile city 15 bodies   # winged alone, for perf
//! target/release/spatial-peers profile terrain 120 features 5 8   # each centre 8 times
//! target/release/spatial-peers profile-build terrain 5   # winged's builds alone
//! target/release/spatial-peers profile-moves 2000        # winged's moves, and a read
//! target/release/spatial-peers profile-phases 120        # a terrain query, step by step
//! ```
//!
//! Data (`bench/spatial/data.rs`): a closed terrain solid of 1,000,000 triangles and a
//! city of 100,000 boxes. For each: build time (median of 3), bytes held (a counting
//! allocator: live bytes after the build minus before, build temporaries freed), sphere
//! queries at radii calibrated for about 15 and about 120 hits (p50 / p99 / mean of
//! 10,000 queries each timed alone), and for the city the cost of moving one body (300
//! distinct bodies, one after the other, the same moves for every index).
//!
//! rstar and parry3d answer the candidates their tree finds for the ball's bounding box
//! and keep those that pass an exact test: for triangles [`data::ball_meets_triangle`]
//! (the test winged runs on each face, from the same functions), for boxes
//! [`data::Building::meets_ball`]. Before timing, every index's hits are checked equal on
//! 500 queries of each size (and again for the city after the moves).

#[path = "../data.rs"]
mod data;

use std::alloc::{GlobalAlloc, Layout, System};
use std::collections::HashMap;
use std::fmt::Write as _;
use std::sync::Arc;
use std::sync::atomic::{AtomicUsize, Ordering};
use std::time::Instant;

use data::{Building, Terrain, Timings, ball_box, ball_meets_triangle};
use glam::DVec3;
use parry3d::bounding_volume::Aabb as PAabb;
use parry3d::math::Vector as PVec;
use parry3d::partitioning::{Bvh, BvhBuildStrategy};
use rstar::primitives::{GeomWithData, Rectangle};
use rstar::{AABB, RTree};
use winged::model::{Pose, World};
use winged::spatial::{BoxQuery, Detail, Spatial, SphereAnswer, SphereQuery};

// ------------------------------------------------------------------ counting allocator

/// The system allocator, counting the bytes live.
struct Counting;

static LIVE: AtomicUsize = AtomicUsize::new(0);

// SAFETY: every call is forwarded to the system allocator unchanged; only a counter is
// kept beside it.
unsafe impl GlobalAlloc for Counting {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        LIVE.fetch_add(layout.size(), Ordering::Relaxed);
        // SAFETY: forwarded with the caller's layout.
        unsafe { System.alloc(layout) }
    }

    unsafe fn alloc_zeroed(&self, layout: Layout) -> *mut u8 {
        LIVE.fetch_add(layout.size(), Ordering::Relaxed);
        // SAFETY: forwarded with the caller's layout.
        unsafe { System.alloc_zeroed(layout) }
    }

    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        LIVE.fetch_sub(layout.size(), Ordering::Relaxed);
        // SAFETY: `ptr` came from this allocator (hence the system's) with `layout`.
        unsafe { System.dealloc(ptr, layout) }
    }

    unsafe fn realloc(&self, ptr: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
        // SAFETY: forwarded with the caller's arguments.
        let p = unsafe { System.realloc(ptr, layout, new_size) };
        if !p.is_null() {
            LIVE.fetch_add(new_size, Ordering::Relaxed);
            LIVE.fetch_sub(layout.size(), Ordering::Relaxed);
        }
        p
    }
}

#[global_allocator]
static ALLOCATOR: Counting = Counting;

fn live() -> usize {
    LIVE.load(Ordering::Relaxed)
}

// ----------------------------------------------------------------------------- helpers

const QUERIES: usize = 10_000;
const CALIBRATION: usize = 300;
const CHECKED: usize = 500;
const MOVES: usize = 300;
const WARM: usize = 10_000;

/// Builds three times: the median time in seconds, the last structure, and the bytes
/// it holds (live bytes after the last build minus before it).
fn build<T>(mut f: impl FnMut() -> T) -> (T, f64, usize) {
    let mut times = Vec::new();
    let mut last = None;
    for _ in 0..3 {
        drop(last.take());
        let before = live();
        let t = Instant::now();
        let x = f();
        times.push(t.elapsed().as_secs_f64());
        let bytes = live().saturating_sub(before);
        last = Some((x, bytes));
    }
    times.sort_by(f64::total_cmp);
    let (x, bytes) = last.expect("built");
    (x, times[1], bytes)
}

/// An `f32` box holding the `f64` box `lo..=hi` (each bound rounded outward, as
/// winged's own hierarchy rounds its boxes).
fn parry_box(lo: DVec3, hi: DVec3) -> PAabb {
    let (min, max) = winged::spatial::aabb::Aabb::new(lo, hi).to_f32_outward();
    PAabb::new(
        PVec::new(min[0], min[1], min[2]),
        PVec::new(max[0], max[1], max[2]),
    )
}

type Item = GeomWithData<Rectangle<[f64; 3]>, u32>;

fn rstar_item(lo: DVec3, hi: DVec3, i: u32) -> Item {
    GeomWithData::new(Rectangle::from_corners(lo.to_array(), hi.to_array()), i)
}

fn rstar_ball(c: DVec3, r: f64) -> AABB<[f64; 3]> {
    let (lo, hi) = ball_box(c, r);
    AABB::from_corners(lo.to_array(), hi.to_array())
}

fn sorted(mut v: Vec<u32>) -> Vec<u32> {
    v.sort_unstable();
    v
}

fn mb(bytes: usize) -> String {
    format!("{:.1} MB", bytes as f64 / 1e6)
}

/// The table printed at the end: rows of (data set, measure, winged, rstar, parry3d).
/// Timings as a table cell: p50 / p99 (mean).
fn cell(t: Timings) -> String {
    format!("{:.2} / {:.2} ({:.2})", t.p50, t.p99, t.mean)
}

#[derive(Default)]
struct Table {
    rows: Vec<[String; 5]>,
}

impl Table {
    fn row(&mut self, set: &str, what: &str, w: String, r: String, p: String) {
        println!("{set} | {what} | winged {w} | rstar {r} | parry3d {p}");
        self.rows.push([set.into(), what.into(), w, r, p]);
    }

    fn timings(&mut self, set: &str, what: &str, w: Timings, r: Timings, p: Timings) {
        self.row(set, what, cell(w), cell(r), cell(p));
    }

    /// A row of winged's timings alone (the peers have no such answer).
    fn winged_only(&mut self, set: &str, what: &str, w: Timings) {
        self.row(set, what, cell(w), "—".into(), "—".into());
    }

    fn print(&self) {
        let mut s = String::new();
        s.push_str("| data | measure | winged | rstar 0.14 | parry3d 0.31 |\n");
        s.push_str("|---|---|---|---|---|\n");
        for r in &self.rows {
            let _ = writeln!(
                s,
                "| {} | {} | {} | {} | {} |",
                r[0], r[1], r[2], r[3], r[4]
            );
        }
        println!("\n{s}");
        println!("Query rows: p50 / p99 (mean) in µs per query; move rows likewise per move.");
    }
}

fn loadavg() -> String {
    std::fs::read_to_string("/proc/loadavg")
        .map(|s| s.split_whitespace().take(3).collect::<Vec<_>>().join(" "))
        .unwrap_or_default()
}

// ----------------------------------------------------------------------------- terrain

fn terrain(table: &mut Table) {
    let set = "terrain, 1M triangles";
    let terrain = Terrain::new();
    let n = terrain.triangles.len() as u32;
    let (world, _, first) = terrain.world();
    let world = Arc::new(world);

    let (spatial, tw, bw) = build(|| Spatial::build(world.clone()));
    let (rtree, tr, br) = build(|| {
        RTree::bulk_load(
            (0..n)
                .map(|i| {
                    let [a, b, c] = terrain.corners(i);
                    rstar_item(a.min(b).min(c), a.max(b).max(c), i)
                })
                .collect(),
        )
    });
    let (bvh, tp, bp) = build(|| {
        Bvh::from_iter(
            BvhBuildStrategy::Binned,
            (0..n).map(|i| {
                let [a, b, c] = terrain.corners(i);
                (i as usize, parry_box(a.min(b).min(c), a.max(b).max(c)))
            }),
        )
    });
    let ms = |t: f64| format!("{:.0} ms", t * 1e3);
    table.row(set, "build", ms(tw), ms(tr), ms(tp));
    let mesh = terrain.mesh_bytes();
    table.row(
        set,
        "bytes held by the index",
        format!("{} (heap_bytes {})", mb(bw), mb(spatial.heap_bytes())),
        format!("{} (+ {} triangle data)", mb(br), mb(mesh)),
        format!(
            "{} (heap_memory_size {}; + {} triangle data)",
            mb(bp),
            mb(bvh.heap_memory_size()),
            mb(mesh)
        ),
    );

    let winged_q = |c: DVec3, r: f64| -> Vec<u32> {
        let q = SphereQuery::new(c, r).with_detail(Detail::Features);
        let a = spatial.sphere(&q).expect("a valid query");
        a.bodies
            .iter()
            .flat_map(|b| b.faces.iter().flatten())
            .map(|f| (f.id - first) as u32)
            .collect()
    };
    let rstar_q = |c: DVec3, r: f64| -> Vec<u32> {
        let mut out = Vec::new();
        for t in rtree.locate_in_envelope_intersecting(rstar_ball(c, r)) {
            if ball_meets_triangle(&terrain.corners(t.data), c, r) {
                out.push(t.data);
            }
        }
        out
    };
    let parry_q = |c: DVec3, r: f64| -> Vec<u32> {
        let (lo, hi) = ball_box(c, r);
        let b = parry_box(lo, hi);
        let mut out = Vec::new();
        for i in bvh.intersect_aabb(&b) {
            if ball_meets_triangle(&terrain.corners(i), c, r) {
                out.push(i);
            }
        }
        out
    };

    let centers = terrain.centers(QUERIES, 1);
    for target in [15.0, 120.0] {
        let r = data::calibrate(target, &centers[..CALIBRATION], 0.01, 20.0, |c, r| {
            rstar_q(c, r).len()
        });
        for &c in &centers[..CHECKED] {
            let w = sorted(winged_q(c, r));
            assert!(w.iter().all(|&i| i < n), "a wall met at {c}");
            assert_eq!(
                w,
                sorted(rstar_q(c, r)),
                "winged and rstar differ at {c}, r {r}"
            );
            assert_eq!(
                w,
                sorted(parry_q(c, r)),
                "winged and parry3d differ at {c}, r {r}"
            );
        }
        let (w, hw) = data::time_each(&centers, |c| winged_q(c, r).len());
        let (rr, hr) = data::time_each(&centers, |c| rstar_q(c, r).len());
        let (p, hp) = data::time_each(&centers, |c| parry_q(c, r).len());
        assert_eq!(hw, hr);
        assert_eq!(hw, hp);
        table.timings(
            set,
            &format!("sphere, features, radius {r:.3} m, mean {hw:.1} faces"),
            w,
            rr,
            p,
        );
        // The same balls at `bodies` detail: whether the terrain (and which of its
        // walls' bodies) meets each, with its distance; the peers have no such answer.
        let (wb, _) = data::time_each(&centers, |c| {
            let q = SphereQuery::new(c, r).with_detail(Detail::Bodies);
            spatial.sphere(&q).expect("a valid query").bodies.len()
        });
        table.winged_only(set, &format!("sphere, bodies, radius {r:.3} m"), wb);
    }
}

// -------------------------------------------------------------------------------- city

fn city(table: &mut Table) {
    let set = "city, 100k boxes";
    let mut city = data::city();
    let n = city.len() as u32;
    let (world, ids, index) = data::city_world(&city);
    let world = Arc::new(world);

    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .build()
        .expect("a pool");
    let (spatial1, tw1, _) = build(|| pool.install(|| Spatial::build(world.clone())));
    drop(spatial1);
    let (mut spatial, tw, bw) = build(|| Spatial::build(world.clone()));
    let rstar_items = |city: &[Building]| -> Vec<Item> {
        city.iter()
            .enumerate()
            .map(|(i, b)| {
                let (lo, hi) = b.bounds();
                rstar_item(lo, hi, i as u32)
            })
            .collect()
    };
    let (mut rtree, tr, br) = build(|| RTree::bulk_load(rstar_items(&city)));
    let (mut bvh, tp, bp) = build(|| {
        Bvh::from_iter(
            BvhBuildStrategy::Binned,
            city.iter().enumerate().map(|(i, b)| {
                let (lo, hi) = b.bounds();
                (i, parry_box(lo, hi))
            }),
        )
    });
    let ms = |t: f64| format!("{:.0} ms", t * 1e3);
    table.row(
        set,
        "build",
        format!(
            "{} on {} threads ({} on one)",
            ms(tw),
            rayon::current_num_threads(),
            ms(tw1)
        ),
        ms(tr),
        ms(tp),
    );
    let boxes = city.len() * std::mem::size_of::<Building>();
    table.row(
        set,
        "bytes held by the index",
        format!("{} (heap_bytes {})", mb(bw), mb(spatial.heap_bytes())),
        format!("{} (+ {} box data)", mb(br), mb(boxes)),
        format!(
            "{} (heap_memory_size {}; + {} box data)",
            mb(bp),
            mb(bvh.heap_memory_size()),
            mb(boxes)
        ),
    );

    fn winged_q(
        spatial: &Spatial,
        index: &HashMap<u64, u32>,
        c: DVec3,
        r: f64,
        detail: Detail,
    ) -> Vec<u32> {
        let q = SphereQuery::new(c, r).with_detail(detail);
        let a = spatial.sphere(&q).expect("a valid query");
        a.bodies.iter().map(|b| index[&b.id]).collect()
    }
    fn rstar_q(tree: &RTree<Item>, city: &[Building], c: DVec3, r: f64) -> Vec<u32> {
        let mut out = Vec::new();
        for t in tree.locate_in_envelope_intersecting(rstar_ball(c, r)) {
            if city[t.data as usize].meets_ball(c, r) {
                out.push(t.data);
            }
        }
        out
    }
    fn parry_q(bvh: &Bvh, city: &[Building], c: DVec3, r: f64) -> Vec<u32> {
        let (lo, hi) = ball_box(c, r);
        let b = parry_box(lo, hi);
        let mut out = Vec::new();
        for i in bvh.intersect_aabb(&b) {
            if city[i as usize].meets_ball(c, r) {
                out.push(i);
            }
        }
        out
    }
    let check = |spatial: &Spatial, rtree: &RTree<Item>, bvh: &Bvh, city: &[Building], r| {
        for &c in &centers_for_check() {
            let w = sorted(winged_q(spatial, &index, c, r, Detail::Bodies));
            assert_eq!(
                w,
                sorted(rstar_q(rtree, city, c, r)),
                "rstar differs at {c}"
            );
            assert_eq!(
                w,
                sorted(parry_q(bvh, city, c, r)),
                "parry3d differs at {c}"
            );
        }
    };

    let centers = data::city_centers(QUERIES, 2);
    let mut radii = Vec::new();
    for target in [15.0, 120.0] {
        let r = data::calibrate(target, &centers[..CALIBRATION], 1.0, 400.0, |c, r| {
            rstar_q(&rtree, &city, c, r).len()
        });
        radii.push(r);
        check(&spatial, &rtree, &bvh, &city, r);
        let (w, hw) = data::time_each(&centers, |c| {
            winged_q(&spatial, &index, c, r, Detail::Bodies).len()
        });
        let (rr, hr) = data::time_each(&centers, |c| rstar_q(&rtree, &city, c, r).len());
        let (p, hp) = data::time_each(&centers, |c| parry_q(&bvh, &city, c, r).len());
        assert_eq!(hw, hr);
        assert_eq!(hw, hp);
        table.timings(
            set,
            &format!("sphere, bodies, radius {r:.2} m, mean {hw:.1} bodies"),
            w,
            rr,
            p,
        );
        let (wf, _) = data::time_each(&centers, |c| {
            let q = SphereQuery::new(c, r).with_detail(Detail::Features);
            spatial.sphere(&q).expect("a valid query").bodies.len()
        });
        table.winged_only(
            set,
            &format!("sphere, features (faces, edges, vertices of each body), radius {r:.2} m"),
            wf,
        );
    }

    // At features detail the hits are faces, as on the terrain: radii for about 15 and
    // about 120 faces (of any bodies), winged alone (the peers keep bodies only).
    for target in [15.0, 120.0] {
        let r = data::calibrate(target, &centers[..CALIBRATION], 1.0, 400.0, |c, r| {
            data::faces_answered(&spatial, c, r)
        });
        let bodies: usize = centers
            .iter()
            .map(|&c| winged_q(&spatial, &index, c, r, Detail::Bodies).len())
            .sum();
        let (wf, faces) = data::time_each(&centers, |c| data::faces_answered(&spatial, c, r));
        table.winged_only(
            set,
            &format!(
                "sphere, features, radius {r:.2} m, mean {faces:.1} faces of {:.1} bodies",
                bodies as f64 / centers.len() as f64
            ),
            wf,
        );
    }

    // Moves: the same MOVES bodies, shifts and order for every index.
    let mut rng = data::Rng::new(3);
    let moves: Vec<(usize, DVec3)> = (0..MOVES)
        .map(|_| {
            let k = (rng.next_u64() % u64::from(n)) as usize;
            (
                k,
                DVec3::new(rng.range(-5.0, 5.0), rng.range(-5.0, 5.0), 0.0),
            )
        })
        .collect();
    // Each move: the world written (cloned, the body posed) outside the timing, then
    // each index told, in turn (the order rotates, so that none always runs first after
    // the write has filled the caches with the new snapshot).
    let mut current: Arc<World> = world.clone();
    let (mut wns, mut rns, mut pns) = (Vec::new(), Vec::new(), Vec::new());
    for (i, &(k, shift)) in moves.iter().enumerate() {
        let (lo, hi) = city[k].bounds();
        city[k].center += shift;
        let (nlo, nhi) = city[k].bounds();
        let pose = Pose::new(city[k].center, city[k].pose().rotation).expect("a pose");
        let next = data::moved(&current, ids[k], pose);
        let old = rstar_item(lo, hi, k as u32);
        let new = rstar_item(nlo, nhi, k as u32);
        let b = parry_box(nlo, nhi);
        for engine in (0..3).map(|e| (e + i) % 3) {
            match engine {
                0 => {
                    let t = Instant::now();
                    let stats = spatial.sync(next.clone(), Some(&[ids[k]]));
                    wns.push(t.elapsed().as_nanos() as f64);
                    assert_eq!(stats.moved, 1);
                }
                1 => {
                    let t = Instant::now();
                    let gone = rtree.remove(&old);
                    rtree.insert(new);
                    rns.push(t.elapsed().as_nanos() as f64);
                    assert!(gone.is_some());
                }
                _ => {
                    let t = Instant::now();
                    bvh.insert(b, k as u32);
                    pns.push(t.elapsed().as_nanos() as f64);
                }
            }
        }
        current = next;
    }
    table.timings(
        set,
        &format!("move one body: {MOVES} distinct bodies, each after a world write"),
        Timings::of(&mut wns),
        Timings::of(&mut rns),
        Timings::of(&mut pns),
    );

    // Warm: one body moved back and forth between two places, WARM times (an even
    // number, so it ends where it began); the mean per move.
    let k = ids.len() / 2 + data::CITY_NX / 2;
    let a = current.clone();
    let (lo, hi) = city[k].bounds();
    let mut there = city[k];
    there.center += DVec3::new(4.0, 3.0, 0.0);
    let (nlo, nhi) = there.bounds();
    let b = data::moved(&a, ids[k], there.pose());
    let t = Instant::now();
    for i in 0..WARM {
        let w = if i % 2 == 0 { b.clone() } else { a.clone() };
        std::hint::black_box(spatial.sync(w, Some(&[ids[k]])));
    }
    let w = t.elapsed().as_nanos() as f64 / WARM as f64 / 1e3;
    let items = [rstar_item(lo, hi, k as u32), rstar_item(nlo, nhi, k as u32)];
    let t = Instant::now();
    for i in 0..WARM {
        assert!(rtree.remove(&items[i % 2]).is_some());
        rtree.insert(items[(i + 1) % 2]);
    }
    let r = t.elapsed().as_nanos() as f64 / WARM as f64 / 1e3;
    let boxes = [parry_box(nlo, nhi), parry_box(lo, hi)];
    let t = Instant::now();
    for i in 0..WARM {
        bvh.insert(boxes[i % 2], k as u32);
    }
    let p = t.elapsed().as_nanos() as f64 / WARM as f64 / 1e3;
    let f = |x: f64| format!("{x:.2}");
    table.row(
        set,
        &format!("move one body: the same body back and forth, mean of {WARM}"),
        f(w),
        f(r),
        f(p),
    );
    for &r in &radii {
        check(&spatial, &rtree, &bvh, &city, r);
    }
    drop(current);
}

fn centers_for_check() -> Vec<DVec3> {
    data::city_centers(CHECKED, 2)
}

/// How many hits a query answers (faces of the terrain, bodies of the city).
type HitCount = fn(&Spatial, DVec3, f64) -> usize;

/// `profile <terrain|city> <hits> <bodies|features> [seconds] [repeats]`: winged's sphere
/// queries alone in a loop (about `hits` hits each: faces at `features` detail, bodies
/// of the city at `bodies` detail), for `perf record`. With `repeats`
/// above 1, each centre is queried that many times in a row: the repeats find what the
/// first read in cache, so that comparing the mean with `repeats` 1 tells the cost of
/// the misses from the cost of the work.
fn profile(args: &[String]) {
    let set = args.first().map_or("city", String::as_str);
    let target: f64 = args.get(1).and_then(|s| s.parse().ok()).unwrap_or(15.0);
    let detail = match args.get(2).map(String::as_str) {
        Some("bodies") => Detail::Bodies,
        _ => Detail::Features,
    };
    let seconds: f64 = args.get(3).and_then(|s| s.parse().ok()).unwrap_or(10.0);
    let repeats: usize = args.get(4).and_then(|s| s.parse().ok()).unwrap_or(1).max(1);
    let (world, centers, count): (World, Vec<DVec3>, HitCount) = if set == "terrain" {
        let t = Terrain::new();
        let centers = t.centers(QUERIES, 1);
        (t.world().0, centers, data::faces_answered)
    } else {
        let city = data::city();
        (
            data::city_world(&city).0,
            data::city_centers(QUERIES, 2),
            if detail == Detail::Features {
                data::faces_answered
            } else {
                |s, c, r| {
                    let q = SphereQuery::new(c, r).with_detail(Detail::Bodies);
                    s.sphere(&q).expect("a valid query").bodies.len()
                }
            },
        )
    };
    let spatial = Spatial::build(Arc::new(world));
    let hi = if set == "terrain" { 20.0 } else { 400.0 };
    let r = data::calibrate(target, &centers[..CALIBRATION], 0.01, hi, |c, r| {
        count(&spatial, c, r)
    });
    println!("{set}: radius {r:.3} for about {target} hits; querying for {seconds} s");
    if set == "terrain" {
        // How many faces the body's hierarchy leaves for the exact test.
        let shape = terrain_shape(&spatial);
        let sample = &centers[..CALIBRATION];
        let mut visited = 0usize;
        for &c in sample {
            shape.bvh.within(c, r * r, |_| visited += 1);
        }
        println!(
            "{:.1} faces per query in the leaves the hierarchy visits",
            visited as f64 / sample.len() as f64
        );
    } else {
        // How many bodies the top hierarchy leaves for the exact test: those whose world
        // bounds lie within the radius.
        let city = data::city();
        let sample = &centers[..CALIBRATION];
        let within: usize = sample
            .iter()
            .map(|&c| {
                city.iter()
                    .filter(|b| {
                        let (lo, hi) = b.bounds();
                        (lo - c).max(c - hi).max(DVec3::ZERO).length_squared() <= r * r
                    })
                    .count()
            })
            .sum();
        println!(
            "{:.1} bodies per query have bounds within the radius",
            within as f64 / sample.len() as f64
        );
    }
    let start = Instant::now();
    let mut n = 0usize;
    while start.elapsed().as_secs_f64() < seconds {
        for &c in &centers {
            for _ in 0..repeats {
                std::hint::black_box(timed_query(&spatial, c, r, detail));
            }
        }
        n += centers.len() * repeats;
    }
    let us = start.elapsed().as_secs_f64() * 1e6 / n as f64;
    println!("{n} queries, {us:.2} µs each");
}

/// One query of the `profile` loop, apart so that a profiler can count it alone
/// (`valgrind --tool=callgrind --toggle-collect=spatial_peers::timed_query`).
#[inline(never)]
fn timed_query(spatial: &Spatial, c: DVec3, r: f64, detail: Detail) -> SphereAnswer {
    let q = SphereQuery::new(c, r).with_detail(detail);
    spatial.sphere(&q).expect("a valid query")
}

/// `profile-moves [moves] [log2 entries]`: winged's city index alone, one body moved
/// after each world write (the write timed apart, as in the side-by-side run); p50 and
/// mean per move, and per write. For scale, the cost of one memory read on this machine
/// after such a write: a chase of dependent reads through a random cycle of `2^log2`
/// 4-byte entries (2^23, 32 MiB, by default), timed right after another write.
fn profile_moves(args: &[String]) {
    let count: usize = args.first().and_then(|s| s.parse().ok()).unwrap_or(2000);
    let mut city = data::city();
    let (world, ids, _) = data::city_world(&city);
    let mut current = Arc::new(world);
    let mut spatial = Spatial::build(current.clone());
    let mut rng = data::Rng::new(5);
    let mut ns = Vec::with_capacity(count);
    let chase_log2: u32 = args
        .get(1)
        .and_then(|s| s.parse().ok())
        .unwrap_or(23)
        .min(30);
    let cycle = random_cycle(1 << chase_log2, 9);
    let mut reads = Vec::with_capacity(count);
    let mut writes = Vec::with_capacity(count);
    // The index's world, held here too so that no sync frees a world in its timing.
    let mut held = current.clone();
    for _ in 0..count {
        let k = (rng.next_u64() % ids.len() as u64) as usize;
        city[k].center += DVec3::new(rng.range(-5.0, 5.0), rng.range(-5.0, 5.0), 0.0);
        let pose = Pose::new(city[k].center, city[k].pose().rotation).expect("a pose");
        let t = Instant::now();
        let next = data::moved(&current, ids[k], pose);
        writes.push(t.elapsed().as_nanos() as f64);
        let t = Instant::now();
        let stats = spatial.sync(next.clone(), Some(&[ids[k]]));
        ns.push(t.elapsed().as_nanos() as f64);
        assert_eq!(stats.moved, 1);
        // Another write (the same pose again), then CHASE dependent reads.
        current = data::moved(&next, ids[k], pose);
        held = next;
        let mut at = (rng.next_u64() % cycle.len() as u64) as usize;
        let t = Instant::now();
        for _ in 0..CHASE {
            at = cycle[at] as usize;
        }
        reads.push(t.elapsed().as_nanos() as f64 / CHASE as f64);
        std::hint::black_box(at);
    }
    drop(held);
    let t = Timings::of(&mut ns);
    println!(
        "{count} moves after a world write: p50 {:.2} µs, p99 {:.2} µs, {:.2} µs each",
        t.p50, t.p99, t.mean
    );
    let w = Timings::of(&mut writes);
    println!(
        "the world writes themselves (clone, pose the body): p50 {:.2} µs, p99 {:.2} µs",
        w.p50, w.p99
    );
    let r = Timings::of(&mut reads);
    println!(
        "one read of a {} KiB array after a world write, chased {CHASE} deep: p50 {:.0} ns",
        (4usize << chase_log2) >> 10,
        r.p50 * 1e3
    );
}

/// The terrain body's shape (its faces, laid out as the index lays them out), from the
/// world `spatial` was built over.
fn terrain_shape(spatial: &Spatial) -> winged::spatial::shape::BodyShape {
    let (_, body) = spatial
        .world()
        .bodies()
        .find(|(_, n)| n.body.face_count() > 0)
        .expect("the terrain");
    winged::spatial::shape::BodyShape::build(body.body.clone())
}

/// `profile-phases [hits]`: where a terrain query's wall time goes. Over the same
/// centres, in turn and three times: the hierarchy's walk alone (the candidate faces
/// gathered), the walk and a read of every candidate's loci (as the query reads them,
/// prefetched ahead), the whole query at
/// `bodies` and at `features` detail, and the box query of the ball's bounding box at
/// each; each the mean over all centres, in µs.
fn profile_phases(args: &[String]) {
    let target: f64 = args.first().and_then(|s| s.parse().ok()).unwrap_or(120.0);
    let t = Terrain::new();
    let centers = t.centers(QUERIES, 1);
    let spatial = Spatial::build(Arc::new(t.world().0));
    let r = data::calibrate(target, &centers[..CALIBRATION], 0.01, 20.0, |c, r| {
        data::faces_answered(&spatial, c, r)
    });
    let shape = terrain_shape(&spatial);
    println!("terrain: radius {r:.3} for about {target} faces");
    let mean = |f: &mut dyn FnMut(DVec3) -> u64| {
        let start = Instant::now();
        let mut acc = 0u64;
        for &c in &centers {
            acc = acc.wrapping_add(f(c));
        }
        std::hint::black_box(acc);
        start.elapsed().as_secs_f64() * 1e6 / centers.len() as f64
    };
    let r2 = r * r;
    for round in 1..=3 {
        let walk = mean(&mut |c| {
            let mut v: Vec<u32> = Vec::with_capacity(256);
            shape.bvh.within(c, r2, |k| v.push(k as u32));
            v.len() as u64
        });
        let read = mean(&mut |c| {
            let mut v: Vec<u32> = Vec::with_capacity(256);
            shape.bvh.within(c, r2, |k| v.push(k as u32));
            let mut acc = 0u64;
            shape.visit_ahead(&v, |k| {
                acc ^= shape.loop_points(k).fold(0, |a, p| a ^ p.x.to_bits());
            });
            acc
        });
        let spatial = &spatial;
        let whole = |detail: Detail| {
            move |c: DVec3| {
                let q = SphereQuery::new(c, r).with_detail(detail);
                spatial.sphere(&q).expect("a valid query").bodies.len() as u64
            }
        };
        let bodies = mean(&mut whole(Detail::Bodies));
        let features = mean(&mut whole(Detail::Features));
        // The ball's bounding box as a box query, at each detail.
        let boxed = |detail: Detail| {
            move |c: DVec3| {
                let mut q = BoxQuery::new(c - DVec3::splat(r), c + DVec3::splat(r));
                q.detail = detail;
                spatial.aabb(&q).expect("a valid query").bodies.len() as u64
            }
        };
        let box_bodies = mean(&mut boxed(Detail::Bodies));
        let box_features = mean(&mut boxed(Detail::Features));
        println!(
            "round {round}: walk {walk:.2} µs, walk and loci read {read:.2} µs, \
             query at bodies {bodies:.2} µs, at features {features:.2} µs; \
             its box at bodies {box_bodies:.2} µs, at features {box_features:.2} µs"
        );
    }
}

/// Dependent reads per chase in `profile-moves`.
const CHASE: usize = 8;

/// A single cycle through `0..n` in random order (Sattolo's shuffle): `next[i]`.
fn random_cycle(n: usize, seed: u64) -> Vec<u32> {
    let mut rng = data::Rng::new(seed);
    let mut order: Vec<u32> = (0..n as u32).collect();
    for i in (1..n).rev() {
        let j = (rng.next_u64() % i as u64) as usize;
        order.swap(i, j);
    }
    let mut next = vec![0u32; n];
    for w in 0..n {
        next[order[w] as usize] = order[(w + 1) % n];
    }
    next
}

/// `profile-build <terrain|city> [rounds]`: winged's index built again and again over
/// one world, for `perf record`; each build's time, and the two steps of a rebuild away
/// from the index: its fork (the copy taken while the index is locked) and the fresh
/// hierarchy built from the fork.
fn profile_build(args: &[String]) {
    let set = args.first().map_or("terrain", String::as_str);
    let rounds: usize = args.get(1).and_then(|s| s.parse().ok()).unwrap_or(5);
    let world = Arc::new(if set == "terrain" {
        Terrain::new().world().0
    } else {
        data::city_world(&data::city()).0
    });
    for _ in 0..rounds {
        let start = Instant::now();
        let spatial = Spatial::build(world.clone());
        let ms = start.elapsed().as_secs_f64() * 1e3;
        let start = Instant::now();
        let fork = spatial.fork();
        let fork_ms = start.elapsed().as_secs_f64() * 1e3;
        let start = Instant::now();
        let fresh = fork.build();
        let rebuild_ms = start.elapsed().as_secs_f64() * 1e3;
        println!(
            "{set}: {} bodies indexed in {ms:.0} ms; forked in {fork_ms:.2} ms, \
             rebuilt from the fork in {rebuild_ms:.1} ms",
            fresh.len()
        );
    }
}

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    match args.first().map(String::as_str) {
        Some("profile") => return profile(&args[1..]),
        Some("profile-build") => return profile_build(&args[1..]),
        Some("profile-moves") => return profile_moves(&args[1..]),
        Some("profile-phases") => return profile_phases(&args[1..]),
        _ => {}
    }
    let which = args.first().cloned().unwrap_or_default();
    println!(
        "{} cores; load average at start {}; rayon threads {}",
        std::thread::available_parallelism().map_or(0, |n| n.get()),
        loadavg(),
        rayon::current_num_threads()
    );
    let mut table = Table::default();
    if which.is_empty() || which == "terrain" {
        terrain(&mut table);
    }
    if which.is_empty() || which == "city" {
        city(&mut table);
    }
    table.print();
    println!("load average at end {}", loadavg());
}
