// Temporary exploration: how the twin fares against brute-force disk sampling.
use dbuffer::geometry::hull::convex_hull;
use dbuffer::geometry::ray::intersect_triangle;
use dbuffer::geometry::{Branch, DBufferTwin, PreparedCasters, VolumeParams, VtVariant};
use dbuffer::scene::{Camera, DiskLight, Mesh, Object, Scene};
use glam::Vec3;

struct Rng(u64);
impl Rng {
    fn f(&mut self) -> f32 {
        self.0 ^= self.0 << 13; self.0 ^= self.0 >> 7; self.0 ^= self.0 << 17;
        (self.0 >> 40) as f32 / (1u64 << 24) as f32
    }
    fn r(&mut self, a: f32, b: f32) -> f32 { a + (b - a) * self.f() }
}

fn vis(tris: &[[Vec3; 3]], l: &DiskLight, x: Vec3, k: usize, scale: f32) -> f32 {
    let (u, w) = l.basis();
    let mut seen = 0;
    let n = k;
    for i in 0..k {
        let rr = ((i as f32 + 0.5) / k as f32).sqrt() * l.radius * scale;
        let th = i as f32 * 2.399963;
        let s = l.center + rr * (th.cos() * u + th.sin() * w);
        let d = s - x;
        if !tris.iter().any(|t| intersect_triangle(x, d, t).is_some_and(|t| t > 1e-4 && t < 1.0 - 1e-4)) { seen += 1; }
    }
    let n = (n as f32).sqrt() as usize;
    seen as f32 / (n * n) as f32
}

#[test]
fn explore() {
    let mut rng = Rng(0x9e3779b97f4a7c15);
    let (mut bad_umbra, mut bad_lit, mut pen, mut err_sum, mut err_max, mut over01) = (0, 0, 0, 0.0f64, 0.0f64, 0);
    let (mut n_umbra, mut n_lit) = (0, 0); let mut cats = [(0usize, 0.0f64, 0usize); 3];
    for case in 0..40 {
        let centre = Vec3::new(rng.r(-0.5, 0.5), rng.r(1.0, 2.5), rng.r(-0.5, 0.5));
        let size = rng.r(0.3, 1.2);
        let pts: Vec<Vec3> = (0..(6 + (rng.f() * 14.0) as usize)).map(|_| centre + size * Vec3::new(rng.r(-1.,1.), rng.r(-0.5,0.5), rng.r(-1.,1.))).collect();
        let Some(hull) = convex_hull(&pts) else { continue };
        let tilt = Vec3::new(rng.r(-0.4, 0.4), -1.0, rng.r(-0.4, 0.4)).normalize();
        let light = DiskLight { center: Vec3::new(rng.r(-0.5,0.5), 4.0, rng.r(-0.5,0.5)), normal: tilt, radius: rng.r(0.1, 1.2), intensity: 1.0 };
        let ground = Mesh::new(vec![Vec3::new(-20.,0.,-20.), Vec3::new(20.,0.,-20.), Vec3::new(20.,0.,20.), Vec3::new(-20.,0.,20.)], vec![[0,2,1],[0,3,2]]);
        let scene = Scene { name: "t".into(), camera: Camera { eye: Vec3::ONE, target: Vec3::ZERO, fov_y_deg: 45.0 }, light,
            objects: vec![Object { name: "hull".into(), mesh: hull, casts_shadow: true }, Object { name: "ground".into(), mesh: ground, casts_shadow: false }] };
        let prepared = PreparedCasters::new(&scene);
        let geo = prepared.build(&light, &VolumeParams::for_scene(&scene));
        let twin = DBufferTwin::new(&scene, &geo.casters);
        let tris = scene.all_triangles();
        let (mut cb, mut cl, mut cp, mut ce) = (0, 0, 0, 0.0);
        for _ in 0..300 {
            let x = Vec3::new(centre.x + rng.r(-3., 3.), if rng.f() < 0.5 { 0.0 } else { rng.r(0.0, (centre.y - 0.5 * size).max(0.0)) }, centre.z + rng.r(-3., 3.));
            let s = twin.sample(x);
            let v_big = vis(&tris, &light, x, 1024, 1.1);
            if v_big == 0.0 { n_umbra += 1; if s.branch != Branch::Umbra { bad_umbra += 1; cb += 1; if cb <= 3 { println!("  UMBRA? x={x} s={s:?} stats={:?}", geo.stats); } } }
            if v_big == 1.0 { n_lit += 1; if s.branch != Branch::Lit { bad_lit += 1; cl += 1; if cl <= 2 { println!("  LIT? x={x} s={s:?} stats={:?}", geo.stats); } } }
            let v = vis(&tris, &light, x, 1024, 1.0);
            if v > 0.0 && v < 1.0 {
                pen += 1; cp += 1;
                let e = (VtVariant::Exact.apply(s.t) - v as f64).abs();
                err_sum += e; ce += e; let cat = if !s.hidden { 0 } else if (s.texel.s_u - s.texel.u.unwrap_or(0.0)).abs() < 1e-4 { 2 } else { 1 }; cats[cat].0 += 1; cats[cat].1 += e; if e > 0.1 { cats[cat].2 += 1; } err_max = err_max.max(e); if e > 0.1 { over01 += 1; }
            }
        }
        println!("case {case}: r={:.2} size={size:.2} bad_umbra={cb} bad_lit={cl} pen={cp} mae={:.3} warn={:?}", light.radius, ce / cp.max(1) as f64, geo.warnings);
    }
    println!("visible / hidden-quad / hidden-silface: {cats:?}"); println!("umbra {n_umbra} (bad {bad_umbra}), lit {n_lit} (bad {bad_lit}), penumbra {pen}: mae {:.4} max {:.3} >0.1: {over01}", err_sum / pen as f64, err_max);
}
