//! Analytic shapes (Mitsuba's `sphere` and `disk`): light sampling on them against its own
//! density by χ² (a sphere by its visible cone from outside and by area from inside, a
//! sheared disk by area), each with a wrong density it must reject; rays leaving a glass
//! sphere from inside and outside; a smooth glass sphere under a `constant` emitter is
//! invisible (it neither creates nor loses energy), and a grey diffuse sphere or a slightly
//! absorbing glass one in its place is seen; XML spheres and disks are placed as Mitsuba
//! places them; and Embree and obvhs give the same answers on them, single rays and packets
//! alike. Run with `cargo test --profile release-tests --test analytic`
//! (`-- --nocapture` prints every statistic).

// The shared harness, of which this file uses the sphere binning only.
#[allow(dead_code)]
#[path = "../src/sampling/chi2.rs"]
mod chi2;

use chi2::{chi2, chi2_test, Family, SphereBins};
use genpath::accel::{self, AccelKind, Analytic, Ray, TriangleMesh};
use genpath::integrators::{Method, RenderSettings};
use genpath::path::SceneView;
use genpath::scene::SurfacePoint;
use genpath::scene::{Emitters, Scene};
use glam::{DAffine3, DMat3, DVec3, Vec3};
use rand::{Rng, SeedableRng};
use rand_pcg::Pcg64;
use std::f64::consts::PI;
use std::path::Path;

/// The χ² tests in this file that must accept.
const FAMILY: Family = Family { tests: 3 };
const SAMPLES: u64 = 1_000_000;

fn mesh_of(shapes: Vec<Analytic>) -> TriangleMesh {
    TriangleMesh {
        shapes,
        ..Default::default()
    }
}

/// The solid-angle density at `x` of the direction `d` under the emitters' light sampling
/// (`pdf_area_seen_from` at the point `d` meets first), 0 where `d` meets no emitter.
fn pdf_direction(mesh: &TriangleMesh, emitters: &Emitters, x: DVec3, d: DVec3) -> f64 {
    let ray = Ray::new(x.as_vec3(), d.as_vec3(), 0.0, f32::INFINITY);
    let Some((t, n, _, _)) = mesh.shapes[0].intersect(&ray, f64::INFINITY) else {
        return 0.0;
    };
    let y = x + d * t;
    let pdf_area = emitters.pdf_area_seen_from(mesh, x.as_vec3(), y.as_vec3(), 0);
    pdf_area * t * t / n.dot(d).abs()
}

/// Light-sampled directions at `x` as the χ² harness draws them.
fn sample_direction(mesh: &TriangleMesh, emitters: &Emitters, x: DVec3, u: [f64; 3]) -> DVec3 {
    let s = emitters.sample_seen_from(mesh, x.as_vec3(), u.map(|u| u as f32));
    (s.point.as_dvec3() - x).normalize()
}

#[test]
fn a_sphere_seen_from_outside_is_sampled_by_its_cone_and_area_sampling_is_rejected() {
    let (center, radius) = (DVec3::new(1.0, 2.0, 0.5), 0.6);
    let mesh = mesh_of(vec![Analytic::sphere(center, radius, false).unwrap()]);
    let emitters = Emitters::new(&mesh, |_| true);
    let x = DVec3::new(0.3, -0.2, 0.1);
    let axis = (center - x).normalize();
    let sin2 = radius * radius / (center - x).length_squared();
    let h_edge = sin2 / (1.0 + (1.0 - sin2).sqrt());
    let bins = SphereBins::split_at(axis, h_edge, 16, 4, 16);
    let (hist, c) = chi2_test(
        &bins,
        SAMPLES,
        1,
        |u| sample_direction(&mesh, &emitters, x, u),
        |d| pdf_direction(&mesh, &emitters, x, *d),
    );
    FAMILY.accept("sphere from outside", &hist, &c);
    // Every sampled point is one that x sees, on the sphere.
    let mut rng = Pcg64::seed_from_u64(2);
    for _ in 0..10_000 {
        let u = [rng.random(), rng.random(), rng.random()];
        let y = emitters
            .sample_seen_from(&mesh, x.as_vec3(), u)
            .point
            .as_dvec3();
        assert!(((y - center).length() - radius).abs() < 1e-6 * radius);
        assert!(
            (y - center).dot(x - y) >= -1e-6,
            "a point x cannot see: {y}"
        );
    }
    // The classic mistake: the density of area sampling for the cone's points.
    let area = 4.0 * PI * radius * radius;
    let wrong = |d: &DVec3| {
        let ray = Ray::new(x.as_vec3(), d.as_vec3(), 0.0, f32::INFINITY);
        mesh.shapes[0]
            .intersect(&ray, f64::INFINITY)
            .map_or(0.0, |(t, n, _, _)| t * t / (area * n.dot(*d).abs()))
    };
    FAMILY.reject(
        "sphere from outside, area density",
        &chi2(&bins, &hist, wrong),
    );
}

#[test]
fn a_sphere_seen_from_inside_is_sampled_by_area_and_uniform_directions_are_rejected() {
    let (center, radius) = (DVec3::new(-0.5, 0.2, 1.0), 1.3);
    let mesh = mesh_of(vec![Analytic::sphere(center, radius, true).unwrap()]);
    let emitters = Emitters::new(&mesh, |_| true);
    let x = center + DVec3::new(0.5, -0.4, 0.3);
    let bins = SphereBins::equal_area((center - x).normalize(), 16, 32);
    let (hist, c) = chi2_test(
        &bins,
        SAMPLES,
        3,
        |u| sample_direction(&mesh, &emitters, x, u),
        |d| pdf_direction(&mesh, &emitters, x, *d),
    );
    FAMILY.accept("sphere from inside", &hist, &c);
    let uniform = |_: &DVec3| 1.0 / (4.0 * PI);
    FAMILY.reject(
        "sphere from inside, uniform directions",
        &chi2(&bins, &hist, uniform),
    );
}

#[test]
fn a_sheared_disk_is_sampled_by_area_and_the_unsheared_area_is_rejected() {
    let (u, v) = (DVec3::new(0.5, 0.0, 0.0), DVec3::new(0.3, 0.4, 0.0));
    let to_world = DAffine3::from_mat3_translation(
        DMat3::from_cols(u, v, DVec3::Z),
        DVec3::new(0.2, 0.1, 0.0),
    );
    let mesh = mesh_of(vec![Analytic::disk(to_world, false).unwrap()]);
    let emitters = Emitters::new(&mesh, |_| true);
    assert!((emitters.total_area - PI * 0.2).abs() < 1e-12);
    let x = DVec3::new(0.1, 0.2, 0.6);
    let axis = (to_world.translation - x).normalize();
    // A cap about the disk's centre that holds all of it.
    let h_edge = (0..360)
        .map(|i| {
            let a = f64::from(i) * PI / 180.0;
            let p = to_world.transform_point3(DVec3::new(a.cos(), a.sin(), 0.0));
            1.0 - (p - x).normalize().dot(axis)
        })
        .fold(0.0, f64::max)
        * 1.05;
    let bins = SphereBins::split_at(axis, h_edge, 16, 2, 32);
    let (hist, c) = chi2_test(
        &bins,
        SAMPLES,
        5,
        |u| sample_direction(&mesh, &emitters, x, u),
        |d| pdf_direction(&mesh, &emitters, x, *d),
    );
    FAMILY.accept("sheared disk", &hist, &c);
    // The area of the disk as if its axes were orthogonal: π |u| |v|.
    let wrong_area = PI * u.length() * v.length();
    let wrong =
        |d: &DVec3| pdf_direction(&mesh, &emitters, x, *d) * emitters.total_area / wrong_area;
    FAMILY.reject("sheared disk, unsheared area", &chi2(&bins, &hist, wrong));
}

fn scene_dir() -> tempfile::TempDir {
    tempfile::tempdir().unwrap()
}

/// A scene of one sphere (BSDF `bsdf`, centre `center`, radius `radius`) under a `constant`
/// emitter of radiance `0.5, 0.7, 1`, seen whole by a 32² camera, at most 64 bounces.
fn sphere_under_sky(dir: &Path, bsdf: &str, center: [f64; 3], radius: f64) -> Scene {
    let [cx, cy, cz] = center;
    let origin = format!("{cx}, {cy}, {}", cz + 4.0 * radius);
    let text = format!(
        r#"<scene version="3.0.0">
    <integrator type="path"><integer name="max_depth" value="65"/></integrator>
    <sensor type="perspective">
        <float name="fov" value="35"/>
        <transform name="to_world"><lookat origin="{origin}" target="{cx}, {cy}, {cz}" up="0, 1, 0"/></transform>
        <film type="hdrfilm"><integer name="width" value="32"/><integer name="height" value="32"/><rfilter type="box"/></film>
    </sensor>
    <emitter type="constant"><rgb name="radiance" value="0.5, 0.7, 1"/></emitter>
    <shape type="sphere">
        <point name="center" x="{cx}" y="{cy}" z="{cz}"/>
        <float name="radius" value="{radius}"/>
        {bsdf}
    </shape>
</scene>
"#
    );
    let path = dir.join("sky.xml");
    std::fs::write(&path, text).unwrap();
    Scene::load(&path).unwrap_or_else(|e| panic!("{e}"))
}

const GLASS: &str = r#"<bsdf type="dielectric"><float name="int_ior" value="1.5"/></bsdf>"#;

/// Rays leaving a glass sphere's surface: inwards they meet the sphere again at the far end
/// of their chord, outwards they meet nothing (only the sphere is in the scene), at several
/// scales and positions.
#[test]
fn rays_leave_a_sphere_without_meeting_it_again_where_they_leave() {
    let dir = scene_dir();
    for (center, radius) in [
        ([0.0, 0.0, 0.0], 1.0),
        ([3.0, -2.0, 1.0], 0.25),
        ([0.01, 0.0, 0.0], 0.01),
        ([200.0, 100.0, -50.0], 30.0),
    ] {
        let scene = sphere_under_sky(dir.path(), GLASS, center, radius);
        let accel = accel::build(AccelKind::default_available(), &scene.mesh).unwrap();
        let view = SceneView::new(&scene, accel.as_ref());
        let c = DVec3::from(center);
        let mut rng = Pcg64::seed_from_u64(7);
        let mut counts = Default::default();
        for _ in 0..20_000 {
            let n = genpath::math::uniform_sphere(rng.random(), rng.random()).as_dvec3();
            let x = SurfacePoint::flat((c + n * radius).as_vec3(), n.as_vec3(), 0);
            let mut d = genpath::math::uniform_sphere(rng.random(), rng.random());
            if d.dot(x.ng).abs() < 1e-3 {
                continue;
            }
            // Inwards: the far end of the chord, 2 r |cos| away.
            if d.dot(x.ng) > 0.0 {
                d = -d;
            }
            let ray = view.spawn(&x, d);
            let hit = view.trace(&ray, &mut counts);
            let hit = hit.unwrap_or_else(|| panic!("r {radius}: an inward ray left the sphere"));
            // The far root from the ray's origin (pushed inside by the offset), in f64.
            let (o, dd) = (ray.origin.as_dvec3() - c, d.as_dvec3());
            let b = o.dot(dd);
            let far = -b + (b * b - (o.length_squared() - radius * radius)).sqrt();
            let expected = ray.origin.as_dvec3() + dd * far;
            let error = (hit.p.as_dvec3() - expected).length();
            assert!(
                error < 1e-5 * radius.max(c.abs().max_element()),
                "r {radius}: met again {error} away from the far end of the chord"
            );
            assert!(far > 1e-3 * radius, "r {radius}: met again where it left");
            // Outwards: nothing.
            assert!(view.trace(&view.spawn(&x, -d), &mut counts).is_none());
        }
    }
}

/// The mean of `method`'s image and, per 8 × 8 block and channel, the largest |z| of its
/// block mean against `expected`.
fn render_against(scene: &Scene, method: Method, expected: Vec3) -> (Vec3, f64) {
    let accel = accel::build(AccelKind::default_available(), &scene.mesh).unwrap();
    let view = SceneView::new(scene, accel.as_ref());
    let settings = RenderSettings {
        method,
        spp: 64,
        max_bounces: scene.render.max_bounces,
        seed: 5,
        progress: false,
        shard: Default::default(),
        control: Default::default(),
        learning: None,
    };
    let config = genpath::integrators::Settings::default();
    let film = genpath::integrators::prepare(&view, &config, &settings)
        .unwrap()
        .render(&view, &settings);
    let (w, h) = (film.image.width, film.image.height);
    let mut max_z = 0.0f64;
    for by in (0..h).step_by(8) {
        for bx in (0..w).step_by(8) {
            for c in 0..3 {
                let (mut sum, mut var) = (0.0, 0.0);
                for y in by..by + 8 {
                    for x in bx..bx + 8 {
                        sum += f64::from(film.image.get(x, y)[c]);
                        var += film.variance_of_mean[(y * w + x) as usize][c];
                    }
                }
                let diff = (sum / 64.0 - f64::from(expected[c])).abs();
                // A floor on the error for blocks every sample of which is exactly the sky.
                let se = var.sqrt() / 64.0 + 1e-4 * f64::from(expected[c]);
                max_z = max_z.max(diff / se);
            }
        }
    }
    let mean = film
        .image
        .pixels
        .iter()
        .fold(Vec3::ZERO, |m, p| m + Vec3::from(*p))
        / (w * h) as f32;
    (mean, max_z)
}

/// A lossless glass sphere under a uniform sky is invisible: every block of the image is the
/// sky's radiance (within a 99.9 % interval, Šidák-corrected over blocks and channels), for
/// `pt` and `srt`. A grey diffuse sphere, and glass that transmits 97 %, are seen.
#[test]
fn a_glass_sphere_under_a_constant_sky_is_invisible_and_grey_or_absorbing_ones_are_not() {
    let dir = scene_dir();
    let sky = Vec3::new(0.5, 0.7, 1.0);
    let comparisons = 16 * 3;
    let alpha = 1.0 - 0.999f64.powf(1.0 / comparisons as f64);
    let critical = statrs::distribution::ContinuousCDF::inverse_cdf(
        &statrs::distribution::Normal::new(0.0, 1.0).unwrap(),
        1.0 - alpha / 2.0,
    );
    let glass = sphere_under_sky(dir.path(), GLASS, [0.0, 0.0, 0.0], 1.0);
    for method in [Method::Pt, Method::Srt] {
        let (mean, z) = render_against(&glass, method, sky);
        eprintln!("glass, {method:?}: mean {mean}, max |z| {z:.2} (critical {critical:.2})");
        assert!(
            z < critical,
            "{method:?}: the glass sphere is seen (|z| {z:.2})"
        );
        assert!(
            ((mean - sky).abs() / sky).max_element() < 0.01,
            "{method:?}: {mean}"
        );
    }
    let wrong: [(&str, &str); 2] = [
        (
            "grey",
            r#"<bsdf type="twosided"><bsdf type="diffuse"><rgb name="reflectance" value="0.5"/></bsdf></bsdf>"#,
        ),
        (
            "absorbing",
            r#"<bsdf type="dielectric"><float name="int_ior" value="1.5"/><rgb name="specular_transmittance" value="0.97"/></bsdf>"#,
        ),
    ];
    for (what, bsdf) in wrong {
        let scene = sphere_under_sky(dir.path(), bsdf, [0.0, 0.0, 0.0], 1.0);
        let (mean, z) = render_against(&scene, Method::Pt, sky);
        eprintln!("{what}: mean {mean}, max |z| {z:.2} (critical {critical:.2})");
        assert!(z > critical, "the {what} sphere is not seen (|z| {z:.2})");
    }
}

/// Embree and obvhs on spheres and disks among triangles: the same primitive and `t` on
/// random rays (within 1e-4 relative on triangles, bit for bit where a sphere or disk is
/// hit), the same any-hit answers, and packets answered as single rays.
#[cfg(all(feature = "embree", feature = "obvhs"))]
#[test]
fn embree_and_obvhs_agree_on_spheres_and_disks() {
    use genpath::accel::{Accel, BvhAccel, Coherence, EmbreeAccel, PACKET_SIZE};
    let mut mesh = TriangleMesh::new(
        vec![
            Vec3::new(-2.0, -1.0, -2.0),
            Vec3::new(2.0, -1.0, -2.0),
            Vec3::new(2.0, -1.0, 2.0),
            Vec3::new(-2.0, -1.0, 2.0),
        ],
        vec![[0, 2, 1], [0, 3, 2]],
    );
    let disk = DAffine3::from_scale_rotation_translation(
        DVec3::new(0.7, 0.4, 1.0),
        glam::DQuat::from_rotation_x(1.0),
        DVec3::new(0.5, 0.3, -0.4),
    );
    mesh.shapes = vec![
        Analytic::sphere(DVec3::new(0.0, 0.0, 0.0), 0.8, false).unwrap(),
        Analytic::sphere(DVec3::new(1.2, 0.5, 0.3), 0.3, true).unwrap(),
        Analytic::sphere(DVec3::new(-1.0, -0.5, 1.0), 0.5, false).unwrap(),
        Analytic::disk(disk, false).unwrap(),
        Analytic::disk(DAffine3::from_translation(DVec3::new(-0.5, 1.2, 0.0)), true).unwrap(),
    ];
    let embree = EmbreeAccel::new(&mesh).unwrap();
    let bvh = BvhAccel::new(&mesh);
    let mut rng = Pcg64::seed_from_u64(11);
    let first_shape = mesh.triangles.len() as u32;
    let (mut shape_hits, mut rays) = (0, Vec::new());
    for i in 0..20_000 {
        let origin = Vec3::new(
            rng.random_range(-2.5..2.5),
            rng.random_range(-0.9..2.0),
            rng.random_range(-2.5..2.5),
        );
        // Half aimed at a shape's centre, so that many rays meet a sphere or a disk.
        let dir = if i % 2 == 0 {
            genpath::math::uniform_sphere(rng.random(), rng.random())
        } else {
            let target = [
                Vec3::ZERO,
                Vec3::new(1.2, 0.5, 0.3),
                Vec3::new(0.5, 0.3, -0.4),
            ][i % 3];
            (target - origin).normalize()
                + 0.3 * genpath::math::uniform_sphere(rng.random(), rng.random())
        };
        let tmax = if i % 5 == 0 {
            rng.random_range(0.1..3.0)
        } else {
            f32::INFINITY
        };
        let ray = Ray::new(origin, dir, 0.0, tmax);
        let (a, b) = (embree.intersect(&ray), bvh.intersect(&ray));
        match (a, b) {
            (None, None) => {}
            (Some(a), Some(b)) => {
                assert_eq!(a.prim, b.prim, "{ray:?}");
                if a.prim >= first_shape {
                    assert_eq!(a, b, "{ray:?}");
                    shape_hits += 1;
                } else {
                    assert!((a.t - b.t).abs() <= 1e-4 * a.t.max(1.0), "{ray:?}");
                }
            }
            _ => panic!("{ray:?}: {a:?} against {b:?}"),
        }
        assert_eq!(embree.occluded(&ray), bvh.occluded(&ray), "{ray:?}");
        assert_eq!(embree.occluded(&ray), a.is_some(), "{ray:?}");
        rays.push(ray);
    }
    assert!(
        shape_hits > 5_000,
        "only {shape_hits} rays met a sphere or a disk"
    );
    for chunk in rays.chunks(PACKET_SIZE) {
        for accel in [&embree as &dyn Accel, &bvh] {
            let mut hits = vec![None; chunk.len()];
            let mut blocked = vec![false; chunk.len()];
            for coherence in [Coherence::Coherent, Coherence::Incoherent] {
                accel.intersect_packet(chunk, &mut hits, coherence);
                accel.occluded_packet(chunk, &mut blocked, coherence);
                for ((ray, hit), blocked) in chunk.iter().zip(&hits).zip(&blocked) {
                    assert_eq!(
                        *hit,
                        accel.intersect(ray),
                        "{} packet {ray:?}",
                        accel.name()
                    );
                    assert_eq!(
                        *blocked,
                        accel.occluded(ray),
                        "{} packet {ray:?}",
                        accel.name()
                    );
                }
            }
        }
    }
}

/// The shapes of an XML scene whose shapes are `shapes` (beside a constant sky), and its
/// warnings.
fn xml_shapes(dir: &Path, shapes: &str) -> (Vec<Analytic>, Vec<String>) {
    let text = format!(
        r#"<scene version="3.0.0">
    <sensor type="perspective">
        <transform name="to_world"><lookat origin="0, 0, 9" target="0, 0, 0" up="0, 1, 0"/></transform>
        <film type="hdrfilm"><integer name="width" value="8"/><integer name="height" value="8"/><rfilter type="box"/></film>
    </sensor>
    <emitter type="constant"><rgb name="radiance" value="1"/></emitter>
    {shapes}
</scene>
"#
    );
    let path = dir.join("shapes.xml");
    std::fs::write(&path, text).unwrap();
    let scene = Scene::load(&path).unwrap_or_else(|e| panic!("{e}"));
    (scene.mesh.shapes.clone(), scene.warnings.clone())
}

/// Spheres and disks are placed as Mitsuba places them: a sphere by
/// `to_world · translate(center) · scale(radius)`, its radius the image of the x axis (with
/// Mitsuba's warning where `to_world` scales unevenly); a disk's normal is `to_world`'s
/// inverse transpose applied to +z, flipped by `flip_normals`.
#[test]
fn xml_spheres_and_disks_are_placed_as_mitsuba_places_them() {
    let dir = scene_dir();
    let (shapes, warnings) = xml_shapes(
        dir.path(),
        r#"<shape type="sphere">
            <point name="center" x="1" y="0" z="0"/><float name="radius" value="0.5"/>
            <transform name="to_world"><scale value="2"/><translate y="1"/></transform>
        </shape>"#,
    );
    // The texture coordinates turn with to_world's linear part.
    let expected = Analytic::sphere(DVec3::new(2.0, 1.0, 0.0), 1.0, false)
        .and_then(|s| s.turned(glam::DMat3::from_diagonal(DVec3::splat(2.0))))
        .unwrap();
    assert_eq!(shapes, vec![expected]);
    assert!(warnings.is_empty(), "{warnings:?}");
    let (shapes, warnings) = xml_shapes(
        dir.path(),
        r#"<shape type="sphere"><transform name="to_world"><scale x="3"/></transform><boolean name="flip_normals" value="true"/></shape>"#,
    );
    assert_eq!(
        shapes,
        vec![Analytic::sphere(DVec3::ZERO, 3.0, true)
            .and_then(|s| s.turned(glam::DMat3::from_diagonal(DVec3::new(3.0, 1.0, 1.0))))
            .unwrap()]
    );
    assert!(
        warnings.iter().any(|w| w.contains("unevenly")),
        "{warnings:?}"
    );
    let (shapes, _) = xml_shapes(
        dir.path(),
        r#"<shape type="disk"><transform name="to_world"><scale x="2" y="0.5"/><rotate x="1" angle="90"/></transform></shape>
           <shape type="disk"><boolean name="flip_normals" value="true"/></shape>"#,
    );
    assert_eq!(shapes.len(), 2);
    // Rotating +z by 90° about x gives −y.
    assert!((shapes[0].normal_at(DVec3::ZERO) - DVec3::NEG_Y).length() < 1e-12);
    assert!((shapes[0].area() - PI).abs() < 1e-12);
    assert_eq!(shapes[1].normal_at(DVec3::ZERO), DVec3::NEG_Z);
}
