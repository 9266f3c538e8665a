//! `cargo bench --bench peers`: raylab against a peer, on the same rays and the same machine.
//!
//! The peer is [obvhs](https://crates.io/crates/obvhs): its compressed 8-wide BVH (CWBVH,
//! `build_cwbvh_from_tris`, traversed 4 nodes at a time with SIMD) and its binary BVH
//! (`build_bvh2_from_tris`), both built with `BvhBuildParams::medium_build()` (the preset its
//! examples use: PLOC, then reinsertion), the triangles reordered by its `primitive_indices`
//! as its examples do, and its Möller–Trumbore `Triangle::intersect`.
//!
//! For each scene (cornell, bunny, teapot, terrain) the same triangles go to raylab (the
//! structure its renderer uses, `AccelKind::Auto` with the CPU's best kernels) and to obvhs,
//! and four sets of rays are traced by each:
//!
//! * `primary`: the default camera's rays through every pixel centre at 512 × 512, closest hit;
//! * `shadow`: the lab stage's shadow rays from those hits to the light, any hit below `t_max`;
//! * `bounce`: one cosine-distributed diffuse bounce from every primary hit
//!   ([`raylab_core::bench::bounce_rays`]), closest hit: what the path tracer casts after the first
//!   bounce;
//! * `random`: 512² rays with origins uniform inside the room and directions uniform over the
//!   sphere ([`raylab_core::bench::random_rays_in_room`]), closest hit.
//!
//! raylab is called as its integrators call it: batches of [`BATCH`] rays through
//! `Scene::closest_intersections` / `Scene::occluded_many` (its figure), and, for comparison,
//! one ray a call (`Scene::closest_intersection` / `Scene::occluded`). obvhs's rays are made
//! from raylab's inside the timed loop (as a renderer would), `t_min` 0.
//!
//! Each figure is the median of `--reps` timed runs after a warm-up, the tracers alternating
//! run by run so that a busy moment of the machine falls on all of them alike; on a 1-thread
//! rayon pool and on one of all cores. On one thread the runs are timed by the tracing
//! thread's CPU time (`CLOCK_THREAD_CPUTIME_ID`), so other processes taking the core (this
//! machine is shared) do not count; on several, by the wall clock. `agree` is the share of rays on which raylab and the
//! peer give the same answer: for closest hits the same triangle (or both a miss, or the same
//! `t` within 1e-4 relative where two triangles tie, as along a shared edge); for shadow rays
//! the same blocked or not.
//!
//! ```sh
//! cargo bench --bench peers                    # every scene, tables
//! cargo bench --bench peers -- bunny terrain   # some scenes
//! cargo bench --bench peers -- --json          # one JSON object a line
//! cargo bench --bench peers -- --reps=15 --threads=1,2
//! ```

use std::time::{Duration, Instant};

use obvhs::BvhBuildParams;
use obvhs::bvh2::Bvh2;
use obvhs::bvh2::builder::build_bvh2_from_tris;
use obvhs::cwbvh::CwBvh;
use obvhs::cwbvh::builder::build_cwbvh_from_tris;
use obvhs::ray::{Ray as PeerRay, RayHit};
use obvhs::triangle::Triangle as PeerTriangle;
use raylab_core::base::geometry::Ray;
use raylab_core::bench::{bounce_rays, median_ms, random_rays_in_room, scene_bounds};
use raylab_core::shapes::accel::{Accel, AccelKind};
use raylab_core::shapes::scene::{Scene, SceneChoice};
use raylab_core::test_support::{lab_settings, primary_rays, shadow_rays};
use raylab_core::transport::integrator::BATCH;
use rayon::prelude::*;

const SCENES: [SceneChoice; 4] = [
    SceneChoice::Cornell,
    SceneChoice::Bunny,
    SceneChoice::Teapot,
    SceneChoice::Terrain,
];
const SIZE: u32 = 512;
const SEED: u64 = 0x5eed;
/// Rays per parallel task (as `raylab_core::bench::trace_primary` splits them).
const CHUNK: usize = 1024;

/// One ray's answer: the triangle hit and its `t` (closest hits), or whether it is blocked
/// (shadow rays: index 0 for blocked).
#[derive(Clone, Copy, Debug, PartialEq)]
struct Answer {
    index: u32,
    t: f32,
}

impl Answer {
    const MISS: Answer = Answer {
        index: u32::MAX,
        t: f32::INFINITY,
    };
    const BLOCKED: Answer = Answer { index: 0, t: 0.0 };

    fn blocked(yes: bool) -> Answer {
        if yes { Answer::BLOCKED } else { Answer::MISS }
    }

    /// The same answer, allowing a tie between two triangles at the same distance.
    fn agrees(self, other: Answer) -> bool {
        self.index == other.index
            || (self.index != u32::MAX
                && other.index != u32::MAX
                && (self.t - other.t).abs() <= 1e-4 * self.t.abs().max(other.t.abs()))
    }
}

/// A set of rays and the question asked of each.
enum Rays {
    Closest(Vec<Ray>),
    /// Shadow rays with their `t_max`: is anything in between?
    Shadow(Vec<(Ray, f32)>),
}

impl Rays {
    fn len(&self) -> usize {
        match self {
            Rays::Closest(r) => r.len(),
            Rays::Shadow(r) => r.len(),
        }
    }
}

/// obvhs's structures over one scene's triangles (reordered by each structure's
/// `primitive_indices`, as obvhs's examples do, so a leaf's triangles are contiguous).
struct Peer {
    cwbvh: CwBvh,
    cw_triangles: Vec<PeerTriangle>,
    bvh2: Bvh2,
    bvh2_triangles: Vec<PeerTriangle>,
}

/// Who traces.
#[derive(Clone, Copy, Debug, PartialEq)]
enum Tracer {
    /// raylab, batches of [`BATCH`] rays, as its integrators call it.
    Raylab,
    /// raylab, one ray a call.
    RaylabSingle,
    Cwbvh,
    Bvh2,
}

const TRACERS: [Tracer; 4] = [
    Tracer::Raylab,
    Tracer::RaylabSingle,
    Tracer::Cwbvh,
    Tracer::Bvh2,
];

/// A raylab vector as obvhs's (obvhs uses another version of glam: `Vec3A`).
fn v3<V: From<[f32; 3]>>(v: glam::Vec3) -> V {
    v.to_array().into()
}

fn peer_ray(ray: &Ray, t_max: f32) -> PeerRay {
    PeerRay::new(v3(ray.origin), v3(ray.direction), 0.0, t_max)
}

impl Peer {
    fn build(triangles: &[PeerTriangle]) -> (Peer, f64, f64) {
        let params = BvhBuildParams::medium_build();
        let start = Instant::now();
        let cwbvh = build_cwbvh_from_tris(triangles, params, &mut Duration::default());
        let cw_triangles = cwbvh
            .primitive_indices
            .iter()
            .map(|&i| triangles[i as usize])
            .collect();
        let cw_ms = start.elapsed().as_secs_f64() * 1e3;
        let start = Instant::now();
        let bvh2 = build_bvh2_from_tris(triangles, params, &mut Duration::default());
        let bvh2_triangles = bvh2
            .primitive_indices
            .iter()
            .map(|&i| triangles[i as usize])
            .collect();
        let bvh2_ms = start.elapsed().as_secs_f64() * 1e3;
        let peer = Peer {
            cwbvh,
            cw_triangles,
            bvh2,
            bvh2_triangles,
        };
        (peer, cw_ms, bvh2_ms)
    }
}

/// Traces every ray of `rays` with `tracer`, in parallel on the current pool, into `out`.
fn trace(tracer: Tracer, scene: &Scene, peer: &Peer, rays: &Rays, out: &mut [Answer]) {
    match rays {
        Rays::Closest(rays) => rays
            .par_chunks(CHUNK)
            .zip(out.par_chunks_mut(CHUNK))
            .for_each(|(rays, out)| closest(tracer, scene, peer, rays, out)),
        Rays::Shadow(rays) => rays
            .par_chunks(CHUNK)
            .zip(out.par_chunks_mut(CHUNK))
            .for_each(|(rays, out)| shadow(tracer, scene, peer, rays, out)),
    }
}

fn closest(tracer: Tracer, scene: &Scene, peer: &Peer, rays: &[Ray], out: &mut [Answer]) {
    let answer = |hit: Option<raylab_core::shapes::intersect::Intersection>| {
        hit.map_or(Answer::MISS, |h| Answer {
            index: h.triangle_index as u32,
            t: h.distance,
        })
    };
    match tracer {
        Tracer::Raylab => {
            let mut hits = [None; BATCH];
            for (rays, out) in rays.chunks(BATCH).zip(out.chunks_mut(BATCH)) {
                let hits = &mut hits[..rays.len()];
                scene.closest_intersections(rays, f32::INFINITY, hits);
                for (o, h) in out.iter_mut().zip(hits.iter()) {
                    *o = answer(*h);
                }
            }
        }
        Tracer::RaylabSingle => {
            for (ray, o) in rays.iter().zip(out) {
                *o = answer(scene.closest_intersection(ray, f32::INFINITY));
            }
        }
        Tracer::Cwbvh => {
            let (bvh, tris) = (&peer.cwbvh, &peer.cw_triangles);
            peer_closest(rays, out, &bvh.primitive_indices, |ray, hit| {
                bvh.ray_traverse(ray, hit, |r, id| tris[id].intersect(r))
            });
        }
        Tracer::Bvh2 => {
            let (bvh, tris) = (&peer.bvh2, &peer.bvh2_triangles);
            peer_closest(rays, out, &bvh.primitive_indices, |ray, hit| {
                bvh.ray_traverse(ray, hit, |r, id| tris[id].intersect(r))
            });
        }
    }
}

/// Closest hits by one of obvhs's structures (`traverse`: its `ray_traverse`), as answers
/// naming raylab's triangle indices (`indices`: the structure's `primitive_indices`).
fn peer_closest(
    rays: &[Ray],
    out: &mut [Answer],
    indices: &[u32],
    traverse: impl Fn(PeerRay, &mut RayHit) -> bool,
) {
    for (ray, o) in rays.iter().zip(out) {
        let mut hit = RayHit::none();
        *o = if traverse(peer_ray(ray, f32::INFINITY), &mut hit) {
            Answer {
                index: indices[hit.primitive_id as usize],
                t: hit.t,
            }
        } else {
            Answer::MISS
        };
    }
}

fn shadow(tracer: Tracer, scene: &Scene, peer: &Peer, rays: &[(Ray, f32)], out: &mut [Answer]) {
    match tracer {
        Tracer::Raylab => {
            let mut blocked = [false; BATCH];
            for (rays, out) in rays.chunks(BATCH).zip(out.chunks_mut(BATCH)) {
                let blocked = &mut blocked[..rays.len()];
                scene.occluded_many(rays, blocked);
                for (o, &b) in out.iter_mut().zip(blocked.iter()) {
                    *o = Answer::blocked(b);
                }
            }
        }
        Tracer::RaylabSingle => {
            for ((ray, t_max), o) in rays.iter().zip(out) {
                *o = Answer::blocked(scene.occluded(ray, *t_max));
            }
        }
        Tracer::Cwbvh => {
            let (bvh, tris) = (&peer.cwbvh, &peer.cw_triangles);
            peer_shadow(rays, out, |ray| {
                bvh.ray_traverse_miss(ray, |r, id| tris[id].intersect(r))
            });
        }
        Tracer::Bvh2 => {
            let (bvh, tris) = (&peer.bvh2, &peer.bvh2_triangles);
            peer_shadow(rays, out, |ray| {
                bvh.ray_traverse_miss(ray, |r, id| tris[id].intersect(r))
            });
        }
    }
}

/// Shadow rays by one of obvhs's structures (`misses`: its `ray_traverse_miss`).
fn peer_shadow(rays: &[(Ray, f32)], out: &mut [Answer], misses: impl Fn(PeerRay) -> bool) {
    for ((ray, t_max), o) in rays.iter().zip(out) {
        *o = Answer::blocked(!misses(peer_ray(ray, *t_max)));
    }
}

/// The command line: scene names to keep, `--json`, `--reps=N`, `--threads=A,B`. Other
/// flags (cargo passes `--bench`) are ignored.
struct Args {
    scenes: Vec<String>,
    json: bool,
    reps: usize,
    threads: Vec<usize>,
}

impl Args {
    fn parse() -> Args {
        let all = std::thread::available_parallelism().map_or(1, |n| n.get());
        let mut args = Args {
            scenes: Vec::new(),
            json: false,
            reps: 9,
            threads: if all > 1 { vec![1, all] } else { vec![1] },
        };
        let mut it = std::env::args().skip(1);
        while let Some(a) = it.next() {
            let (flag, value) = match a.split_once('=') {
                Some((f, v)) => (f.to_string(), Some(v.to_string())),
                None => (a.clone(), None),
            };
            let mut value = || value.clone().or_else(|| it.next()).unwrap_or_default();
            match flag.as_str() {
                "--json" => args.json = true,
                "--reps" => args.reps = value().parse().unwrap_or(args.reps).max(1),
                "--threads" => {
                    args.threads = value()
                        .split(',')
                        .filter_map(|n| n.trim().parse().ok())
                        .filter(|&n| n > 0)
                        .collect()
                }
                f if f.starts_with('-') => {}
                _ => args.scenes.push(a),
            }
        }
        args
    }
}

/// One row of the tables.
struct Row {
    threads: usize,
    scene: String,
    set: &'static str,
    rays: usize,
    /// Mrays/s per tracer, in [`TRACERS`] order.
    mrays: [f64; 4],
    /// Share of rays raylab and CWBVH, raylab and BVH2 agree on.
    agree: [f64; 2],
    /// The rays raylab and CWBVH disagree on: hit by raylab only, by CWBVH only, both hit
    /// at different distances (for shadow rays: blocked for raylab only, for CWBVH only).
    disagree: [usize; 3],
    /// What timed the runs ([`Clock::name`]).
    clock: &'static str,
}

struct BuildRow {
    threads: usize,
    scene: String,
    triangles: usize,
    structure: String,
    /// raylab, CWBVH, BVH2.
    ms: [f64; 3],
}

fn main() {
    let args = Args::parse();
    let cpu = cpu_name();
    let obvhs = obvhs_version();
    if !args.json {
        println!(
            "raylab against obvhs {obvhs} on {cpu}; {SIZE}×{SIZE}; median of {} runs; threads {:?}",
            args.reps, args.threads
        );
    }
    let pools: Vec<rayon::ThreadPool> = args
        .threads
        .iter()
        .map(|&n| {
            rayon::ThreadPoolBuilder::new()
                .num_threads(n)
                .build()
                .expect("a rayon pool")
        })
        .collect();
    let mut rows = Vec::new();
    let mut builds = Vec::new();
    for choice in SCENES {
        let name = choice.name();
        if !args.scenes.is_empty() && !args.scenes.contains(&name) {
            continue;
        }
        eprintln!("{name}: loading");
        let scene = match choice.load() {
            Ok(scene) => scene,
            Err(e) => {
                eprintln!("could not load {name}: {e}");
                continue;
            }
        };
        let settings = lab_settings(SIZE, SIZE);
        let primary = primary_rays(&settings.camera);
        let shadows = shadow_rays(&scene, &settings.light, &primary);
        let bounces = bounce_rays(&scene, &primary, SEED);
        let (lo, hi) = scene_bounds(&scene);
        let random = random_rays_in_room(lo, hi, primary.len(), SEED);
        let sets = [
            ("primary", Rays::Closest(primary)),
            ("shadow", Rays::Shadow(shadows)),
            ("bounce", Rays::Closest(bounces)),
            ("random", Rays::Closest(random)),
        ];
        let peer_triangles: Vec<PeerTriangle> = scene
            .triangles
            .iter()
            .map(|t| PeerTriangle {
                v0: v3(t.v0),
                v1: v3(t.v1),
                v2: v3(t.v2),
            })
            .collect();
        let structure = format!(
            "{} {}",
            scene.accel().kind().name(),
            scene.accel().isa().name()
        );
        for (pool, &threads) in pools.iter().zip(&args.threads) {
            eprintln!("{name}: {threads} thread(s): building");
            let (build, peer) = pool.install(|| build_all(&scene, &peer_triangles));
            let build = BuildRow {
                threads,
                scene: name.clone(),
                triangles: scene.triangles.len(),
                structure: structure.clone(),
                ms: build,
            };
            if args.json {
                print_build_json(&build);
            }
            builds.push(build);
            for (set, rays) in &sets {
                eprintln!("{name}: {threads} thread(s): {set}");
                let row = pool.install(|| measure(&scene, &peer, rays, args.reps));
                let row = Row {
                    threads,
                    scene: name.clone(),
                    set,
                    rays: rays.len(),
                    mrays: row.0,
                    agree: row.1,
                    disagree: row.2,
                    clock: row.3,
                };
                if args.json {
                    print_row_json(&row, &cpu, &obvhs);
                }
                rows.push(row);
            }
        }
    }
    if !args.json {
        print_tables(&args.threads, &rows, &builds);
    }
}

/// What the traversals are timed by.
#[derive(Clone, Copy, Debug, PartialEq)]
enum Clock {
    /// The CPU time of the calling thread: on a 1-thread pool every ray is traced on the thread
    /// that [`rayon::ThreadPool::install`] runs the measurement on, so time the core spends on
    /// other processes (this machine is shared) is not counted.
    ThreadCpu,
    /// Wall-clock time, for pools of several threads.
    Wall(Instant),
}

impl Clock {
    /// The thread's CPU time on a 1-thread pool where it can be read, else the wall clock.
    fn for_this_pool() -> Clock {
        if rayon::current_num_threads() == 1 && thread_cpu_time().is_some() {
            Clock::ThreadCpu
        } else {
            Clock::Wall(Instant::now())
        }
    }

    fn now(self) -> Duration {
        match self {
            Clock::ThreadCpu => thread_cpu_time().unwrap_or_default(),
            Clock::Wall(origin) => origin.elapsed(),
        }
    }

    fn name(self) -> &'static str {
        match self {
            Clock::ThreadCpu => "thread CPU time",
            Clock::Wall(_) => "wall-clock time",
        }
    }
}

/// The CPU time the calling thread has used (`CLOCK_THREAD_CPUTIME_ID`).
#[cfg(unix)]
fn thread_cpu_time() -> Option<Duration> {
    let mut ts = libc::timespec {
        tv_sec: 0,
        tv_nsec: 0,
    };
    // SAFETY: `clock_gettime` only writes the `timespec` it is given, which outlives the call.
    let ok = unsafe { libc::clock_gettime(libc::CLOCK_THREAD_CPUTIME_ID, &mut ts) } == 0;
    ok.then(|| Duration::new(ts.tv_sec as u64, ts.tv_nsec as u32))
}

#[cfg(not(unix))]
fn thread_cpu_time() -> Option<Duration> {
    None
}

/// Median build times (ms) of raylab's structure, obvhs's CWBVH and BVH2, on the current pool,
/// and the peer's structures (the last built).
fn build_all(scene: &Scene, triangles: &[PeerTriangle]) -> ([f64; 3], Peer) {
    let runs = if triangles.len() > 100_000 { 3 } else { 9 };
    let raylab: Vec<Duration> = (0..runs)
        .map(|_| {
            Accel::build(
                &scene.triangles,
                AccelKind::Auto,
                raylab_core::shapes::scene::best_isa(),
            )
            .build_time()
        })
        .collect();
    let mut cw = Vec::new();
    let mut b2 = Vec::new();
    let mut last = None;
    for _ in 0..runs {
        let (peer, cw_ms, b2_ms) = Peer::build(triangles);
        cw.push(cw_ms);
        b2.push(b2_ms);
        last = Some(peer);
    }
    let median = |mut v: Vec<f64>| {
        v.sort_by(f64::total_cmp);
        v[v.len() / 2]
    };
    (
        [median_ms(raylab), median(cw), median(b2)],
        last.expect("at least one build"),
    )
}

/// Mrays/s of every tracer (medians; the tracers alternate run by run) and the share of rays
/// on which raylab agrees with CWBVH and with BVH2.
fn measure(
    scene: &Scene,
    peer: &Peer,
    rays: &Rays,
    reps: usize,
) -> ([f64; 4], [f64; 2], [usize; 3], &'static str) {
    let n = rays.len();
    let mut answers = [
        vec![Answer::MISS; n],
        vec![Answer::MISS; n],
        vec![Answer::MISS; n],
        vec![Answer::MISS; n],
    ];
    // Warm-up, which also gives the answers compared.
    for (tracer, out) in TRACERS.iter().zip(answers.iter_mut()) {
        trace(*tracer, scene, peer, rays, out);
    }
    let mut times: [Vec<Duration>; 4] = Default::default();
    let mut scratch = vec![Answer::MISS; n];
    let clock = Clock::for_this_pool();
    for _ in 0..reps {
        for (tracer, times) in TRACERS.iter().zip(times.iter_mut()) {
            let start = clock.now();
            trace(*tracer, scene, peer, rays, &mut scratch);
            times.push(clock.now().saturating_sub(start));
            std::hint::black_box(&scratch);
        }
    }
    let mrays = times.map(|t| {
        let ms = median_ms(t);
        if ms > 0.0 { n as f64 / ms / 1e3 } else { 0.0 }
    });
    let agree = |other: &[Answer]| {
        if n == 0 {
            return 1.0;
        }
        let same = answers[0]
            .iter()
            .zip(other)
            .filter(|(a, b)| a.agrees(**b))
            .count();
        same as f64 / n as f64
    };
    debug_assert!(answers[0] == answers[1], "batched and single calls agree");
    let mut disagree = [0; 3];
    for (a, b) in answers[0].iter().zip(&answers[2]) {
        if !a.agrees(*b) {
            let kind = match (a.index == u32::MAX, b.index == u32::MAX) {
                (false, true) => 0,
                (true, false) => 1,
                _ => 2,
            };
            disagree[kind] += 1;
        }
    }
    (
        mrays,
        [agree(&answers[2]), agree(&answers[3])],
        disagree,
        clock.name(),
    )
}

fn print_tables(threads: &[usize], rows: &[Row], builds: &[BuildRow]) {
    for &t in threads {
        println!();
        let clock = rows.iter().find(|r| r.threads == t).map_or("", |r| r.clock);
        println!("## {t} thread(s): Mrays/s by {clock} (ratio = raylab / obvhs CWBVH)");
        println!();
        println!(
            "| scene | rays | count | raylab | raylab 1 a call | CWBVH | BVH2 | ratio | agree CWBVH | agree BVH2 | not agreed: raylab only / CWBVH only / other |"
        );
        println!("|---|---|---:|---:|---:|---:|---:|---:|---:|---:|---|");
        for r in rows.iter().filter(|r| r.threads == t) {
            let [raylab, single, cw, b2] = r.mrays;
            println!(
                "| {} | {} | {} | {raylab:.1} | {single:.1} | {cw:.1} | {b2:.1} | {:.2}× | {:.3} % | {:.3} % | {} / {} / {} |",
                r.scene,
                r.set,
                r.rays,
                raylab / cw,
                100.0 * r.agree[0],
                100.0 * r.agree[1],
                r.disagree[0],
                r.disagree[1],
                r.disagree[2],
            );
        }
        println!();
        println!("## {t} thread(s): build ms");
        println!();
        println!("| scene | triangles | raylab structure | raylab | CWBVH | BVH2 |");
        println!("|---|---:|---|---:|---:|---:|");
        for b in builds.iter().filter(|b| b.threads == t) {
            println!(
                "| {} | {} | {} | {:.3} | {:.3} | {:.3} |",
                b.scene, b.triangles, b.structure, b.ms[0], b.ms[1], b.ms[2]
            );
        }
    }
}

fn print_row_json(r: &Row, cpu: &str, obvhs: &str) {
    let [raylab, single, cw, b2] = r.mrays;
    let line = serde_json::json!({
        "threads": r.threads,
        "scene": r.scene,
        "rays": r.set,
        "count": r.rays,
        "raylab_mrays_per_s": raylab,
        "raylab_single_mrays_per_s": single,
        "cwbvh_mrays_per_s": cw,
        "bvh2_mrays_per_s": b2,
        "ratio_cwbvh": raylab / cw,
        "agree_cwbvh": r.agree[0],
        "agree_bvh2": r.agree[1],
        "disagree_cwbvh": {
            "raylab_only": r.disagree[0],
            "cwbvh_only": r.disagree[1],
            "different": r.disagree[2],
        },
        "clock": r.clock,
        "cpu": cpu,
        "obvhs": obvhs,
    });
    println!("{line}");
}

fn print_build_json(b: &BuildRow) {
    let line = serde_json::json!({
        "threads": b.threads,
        "scene": b.scene,
        "triangles": b.triangles,
        "raylab_structure": b.structure,
        "raylab_build_ms": b.ms[0],
        "cwbvh_build_ms": b.ms[1],
        "bvh2_build_ms": b.ms[2],
    });
    println!("{line}");
}

/// The CPU's model name (`/proc/cpuinfo`), or "unknown CPU".
fn cpu_name() -> String {
    let info = std::fs::read_to_string("/proc/cpuinfo").unwrap_or_default();
    let field = |key: &str| {
        info.lines()
            .find(|l| l.starts_with(key))
            .and_then(|l| l.split_once(':'))
            .map(|(_, v)| v.trim().to_string())
    };
    let cores = info.lines().filter(|l| l.starts_with("processor")).count();
    match (field("model name"), field("cpu family")) {
        (Some(model), Some(family)) => format!("{model} family {family}, {cores} logical CPUs"),
        (Some(model), None) => format!("{model}, {cores} logical CPUs"),
        _ => "unknown CPU".into(),
    }
}

/// obvhs's version, as Cargo.lock pins it.
fn obvhs_version() -> String {
    let lock = std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/../../Cargo.lock"))
        .unwrap_or_default();
    let mut lines = lock.lines();
    while let Some(line) = lines.next() {
        if line == "name = \"obvhs\""
            && let Some(v) = lines.next().and_then(|l| l.strip_prefix("version = "))
        {
            return v.trim_matches('"').to_string();
        }
    }
    "?".into()
}
