//! Mitsuba's `roughdielectric` (`genpath::scene::material::microfacet::RoughDielectric`) through the
//! one BSDF interface (`brdf`), the first non-delta lobe that transmits: χ² of its samples
//! over the whole sphere (reflection and refraction, GGX and Beckmann, seen from outside
//! (`η > 1`) and from inside (`η < 1`, total internal reflection included), anisotropic,
//! visible normals and the whole distribution with Walter's widened roughness), each with
//! must-reject twins (roughness 3 % off, a density without the refraction's Jacobian `η²`,
//! the index of refraction 3 % off); an energy test (a white furnace, the radiance scaling
//! of refraction undone: reflection plus transmission is at most 1, the sampled albedo is
//! the quadrature of `eval` over the sphere, and albedos without masking or without the
//! refraction's Jacobian are rejected); the generalised reciprocity of radiance-mode
//! transmission; and `eval`/`pdf` against the table Mitsuba 3.9.1 printed
//! (`roughdielectric_mitsuba.txt`, by `scripts/mitsuba_roughdielectric_table.py`).
//!
//! A sample is a direction anywhere on the sphere, or "no direction": a normal that faces
//! away from `wo` (which sampling the whole distribution draws), a reflection below the
//! surface or a refraction above it (where Mitsuba's sample has weight 0). The "no
//! direction" bin's expected probability is the sampled normals' density, times the Fresnel
//! probability of the branch that fails, integrated by its own quadrature over the normals
//! ([`Glass::rejected`]), not `1 − Σ(other bins)`.

use super::*;
use genpath::scene::material::fresnel::fresnel_dielectric;
use genpath::scene::material::microfacet::{Distribution, Microfacet, RoughDielectric};

/// A material of one rough dielectric lobe, white unless told.
fn glass(distribution: Distribution, alpha: (f64, f64), visible: bool, eta: f32) -> Material {
    tinted(distribution, alpha, visible, eta, (Vec3::ONE, Vec3::ONE))
}

fn tinted(
    distribution: Distribution,
    alpha: (f64, f64),
    visible: bool,
    eta: f32,
    (reflectance, transmittance): (Vec3, Vec3),
) -> Material {
    Material {
        name: "rough glass".into(),
        kd: Vec3::ZERO,
        ks: Vec3::ZERO,
        glossy: Glossy::RoughDielectric(RoughDielectric {
            microfacet: Microfacet::new(distribution, alpha.0, alpha.1, visible),
            eta,
            specular_reflectance: reflectance,
            specular_transmittance: transmittance,
        }),
        mirror: false,
        ke: Vec3::ZERO,
        two_sided: true,
        conductor: None,
        dielectric: None,
        textures: None,
    }
}

fn lobe(m: &Material) -> &RoughDielectric {
    match &m.glossy {
        Glossy::RoughDielectric(d) => d,
        _ => unreachable!("a rough dielectric"),
    }
}

/// `m` with its lobe changed by `f`.
fn with_lobe(m: &Material, f: impl Fn(&mut RoughDielectric)) -> Material {
    let mut d = lobe(m).clone();
    f(&mut d);
    Material {
        glossy: Glossy::RoughDielectric(d),
        ..m.clone()
    }
}

fn scaled(m: &Material, k: f64) -> Material {
    with_lobe(m, |d| {
        d.microfacet.alpha_u *= k;
        d.microfacet.alpha_v *= k;
    })
}

/// The rough dielectric seen from `wo` at polar angle `theta_o` about the normal `n`
/// ([`normal`]), from outside (the frame's normal is the stored one) or from inside (`back`:
/// the stored normal is `−n`, and light meets the index `1/η`).
struct Glass {
    m: Material,
    frame: Frame,
    wo: Vec3,
}

impl Glass {
    fn new(m: Material, theta_o: f64, back: bool) -> Self {
        let n = normal();
        let wo = about(n.as_dvec3(), theta_o, 0.3).as_vec3().normalize();
        let s = frame(n.as_dvec3()).0.as_vec3();
        let frame = match back {
            false => Frame::new(n, s),
            true => Frame::behind(n, s),
        };
        Self { m, frame, wo }
    }

    fn beside(&self, m: Material) -> Self {
        Self {
            m,
            frame: self.frame,
            wo: self.wo,
        }
    }

    fn nd(&self) -> DVec3 {
        self.frame.n.as_dvec3().normalize()
    }

    /// `d` in the shading frame (tangent, bitangent `n × s`, normal).
    fn local(&self, d: DVec3) -> DVec3 {
        let (n, s) = (self.nd(), self.frame.s.as_dvec3().normalize());
        DVec3::new(s.dot(d), n.cross(s).dot(d), n.dot(d))
    }

    fn world(&self, l: DVec3) -> DVec3 {
        let (n, s) = (self.nd(), self.frame.s.as_dvec3().normalize());
        s * l.x + n.cross(s) * l.y + n * l.z
    }

    /// The relative index light from `wo` meets.
    fn eta(&self) -> f64 {
        lobe(&self.m).eta_seen(self.frame.back)
    }

    fn pdf(&self, d: DVec3) -> f64 {
        bsdf::pdf(&self.m, self.frame, self.wo, d.as_vec3())
    }

    /// One draw: a direction, or `None`. A sample whose own `pdf` differs from `bsdf::pdf`
    /// (what every density re-evaluates) is a bug.
    fn sample(&self, u: [f64; 3]) -> Option<DVec3> {
        let s = bsdf::sample(&self.m, self.frame, self.wo, u)?;
        assert_eq!(
            s.pdf,
            bsdf::pdf(&self.m, self.frame, self.wo, s.wi),
            "{s:?}"
        );
        assert!(!s.delta);
        Some(s.wi.as_dvec3().normalize())
    }

    /// The mirror direction of `wo` and its refraction through the macrosurface (or, under
    /// total internal reflection, the direction straight below the normal): the axes the
    /// two lobes are binned about.
    fn axes(&self) -> (DVec3, DVec3) {
        let (wo, n) = (self.wo.as_dvec3().normalize(), self.nd());
        let reflected = 2.0 * wo.dot(n) * n - wo;
        let (_, cos_t, _, eta_ti) = fresnel_dielectric(wo.dot(n), self.eta());
        let refracted = if cos_t == 0.0 {
            -n
        } else {
            (n * (wo.dot(n) * eta_ti + cos_t) - wo * eta_ti).normalize()
        };
        (reflected, refracted)
    }

    /// The probability of "no direction": the mass of the sampled normals `m` (density
    /// `p(m | wo)` of the sampling distribution) that face away from `wo`, plus, for those
    /// that face it, the Fresnel reflectance where the reflection goes below the surface and
    /// the transmittance where the refraction goes above it; by adaptive quadrature over
    /// bins of normals about the normal.
    fn rejected(&self) -> f64 {
        let wo = self.local(self.wo.as_dvec3().normalize());
        let d = lobe(&self.m);
        let distr = d.sampling_distribution(wo);
        let eta = self.eta();
        let weight = |world: &DVec3| {
            let m = self.local(*world);
            if m.z <= 0.0 {
                return 0.0;
            }
            let p = distr.pdf(wo, m);
            let cos_i = wo.dot(m);
            if cos_i <= 0.0 {
                return p;
            }
            let (f, cos_t, _, eta_ti) = fresnel_dielectric(cos_i, eta);
            let reflected_z = 2.0 * cos_i * m.z - wo.z;
            let refracted_z = m.z * (cos_i * eta_ti + cos_t) - wo.z * eta_ti;
            let mut lost = 0.0;
            if reflected_z <= 0.0 {
                lost += f;
            }
            if refracted_z >= 0.0 {
                lost += 1.0 - f;
            }
            p * lost
        };
        let alpha = (distr.alpha_u * distr.alpha_v).sqrt();
        let bins = lobe_bins(self.nd(), 2.0 / (alpha * alpha));
        (0..bins.bins()).map(|b| bins.integrate(b, &weight)).sum()
    }
}

/// Directions in `reflect`'s bins above the surface, in `transmit`'s below it, and "no
/// direction" with the probability `none`.
struct GlassOutcomes {
    n: DVec3,
    reflect: SphereBins,
    transmit: SphereBins,
    none: f64,
}

impl GlassOutcomes {
    /// Bins about the two lobes' axes at `g`, resolving a lobe of roughness `alpha`, and
    /// "no direction" with probability `none`.
    fn new(g: &Glass, alpha: f64, none: f64) -> Self {
        let (r, t) = g.axes();
        let ns = 2.0 / (alpha * alpha);
        Self {
            n: g.nd(),
            reflect: lobe_bins(r, ns),
            transmit: lobe_bins(t, ns),
            none,
        }
    }
}

impl Binning for GlassOutcomes {
    type Point = Option<DVec3>;

    fn bins(&self) -> usize {
        self.reflect.bins() + self.transmit.bins() + 1
    }

    fn bin_of(&self, x: &Option<DVec3>) -> Option<usize> {
        match x {
            None => Some(self.bins() - 1),
            Some(d) if d.dot(self.n) > 0.0 => self.reflect.bin_of(d),
            Some(d) if d.dot(self.n) < 0.0 => {
                self.transmit.bin_of(d).map(|b| b + self.reflect.bins())
            }
            Some(_) => None,
        }
    }

    fn integrate(&self, bin: usize, pdf: &dyn Fn(&Option<DVec3>) -> f64) -> f64 {
        let n = self.n;
        let r = self.reflect.bins();
        if bin < r {
            let upper = |d: &DVec3| if d.dot(n) > 0.0 { pdf(&Some(*d)) } else { 0.0 };
            self.reflect.integrate(bin, &upper)
        } else if bin < r + self.transmit.bins() {
            let lower = |d: &DVec3| if d.dot(n) < 0.0 { pdf(&Some(*d)) } else { 0.0 };
            self.transmit.integrate(bin - r, &lower)
        } else {
            self.none
        }
    }
}

/// The lobe's density written out again from its parts, with a knob to break it: the
/// refraction's Jacobian without its `η²`.
fn pdf_without_eta2(g: &Glass, d: DVec3) -> f64 {
    let right = g.pdf(d);
    if g.local(d).z >= 0.0 {
        return right;
    }
    let eta = g.eta();
    right / (eta * eta)
}

/// χ² of the BSDF's samples at `g` against `bsdf::pdf` and [`Glass::rejected`] (must
/// accept), then against each wrong material's (must reject) and a density without the
/// refraction Jacobian's `η²`.
fn check(name: &str, g: &Glass, alpha: f64, seed: u64, wrong: &[(&str, Material)]) {
    let outcomes = GlassOutcomes::new(g, alpha, g.rejected());
    let (hist, c) = chi2_test(
        &outcomes,
        SAMPLES,
        seed,
        |u| g.sample(u),
        on_outcomes(|d| g.pdf(d)),
    );
    let below = hist.counts[outcomes.reflect.bins()..outcomes.bins() - 1]
        .iter()
        .sum::<u64>();
    println!(
        "{name}: η {:.4}, transmitted {:.4} of the draws, no direction in {:.5}, {:.5} expected",
        g.eta(),
        below as f64 / SAMPLES as f64,
        hist.counts[outcomes.bins() - 1] as f64 / SAMPLES as f64,
        outcomes.none
    );
    FAMILY.accept(name, &hist, &c);
    for (what, m) in wrong {
        let w = g.beside(m.clone());
        // The same bins, with the wrong material's "no direction".
        let theirs = GlassOutcomes::new(g, alpha, w.rejected());
        FAMILY.reject(
            &format!("{name} against {what}"),
            &chi2(&theirs, &hist, on_outcomes(|d| w.pdf(d))),
        );
    }
    FAMILY.reject(
        &format!("{name} against a refraction Jacobian without η²"),
        &chi2(&outcomes, &hist, on_outcomes(|d| pdf_without_eta2(g, d))),
    );
}

fn theta(deg: f64) -> f64 {
    deg.to_radians()
}

#[test]
fn ggx_from_outside_visible() {
    let m = glass(Distribution::Ggx, (0.3, 0.3), true, 1.5);
    let g = Glass::new(m.clone(), theta(40.0), false);
    let wrong = [
        ("alpha 3 % wide", scaled(&m, 1.03)),
        ("η 3 % high", with_lobe(&m, |d| d.eta *= 1.03)),
    ];
    check(
        "GGX α 0.3 η 1.5 visible, outside at 40°",
        &g,
        0.3,
        201,
        &wrong,
    );
}

/// From inside at 35° (the critical angle of η = 1.5 is 41.8°): refraction out through the
/// normals that allow it, total internal reflection off the others.
#[test]
fn beckmann_from_inside_visible() {
    let m = glass(Distribution::Beckmann, (0.2, 0.2), true, 1.5);
    let g = Glass::new(m.clone(), theta(35.0), true);
    let wrong = [
        ("alpha 3 % narrow", scaled(&m, 0.97)),
        (
            "the index seen from outside",
            glass(Distribution::Beckmann, (0.2, 0.2), true, 1.0 / 1.5),
        ),
    ];
    check(
        "Beckmann α 0.2 η 1/1.5 visible, inside at 35°",
        &g,
        0.2,
        202,
        &wrong,
    );
}

/// Anisotropic (along the frame's tangent); the twin with `alpha_u` and `alpha_v`
/// exchanged is the lobe turned by 90°.
#[test]
fn ggx_anisotropic_visible() {
    let m = glass(Distribution::Ggx, (0.1, 0.35), true, 1.33);
    let g = Glass::new(m.clone(), theta(55.0), false);
    let wrong = [
        ("alpha 3 % wide", scaled(&m, 1.03)),
        (
            "alpha_u and alpha_v exchanged",
            glass(Distribution::Ggx, (0.35, 0.1), true, 1.33),
        ),
    ];
    check(
        "GGX α (0.1, 0.35) η 1.33 visible, outside at 55°",
        &g,
        (0.1f64 * 0.35).sqrt(),
        203,
        &wrong,
    );
}

/// The whole distribution, with Walter's roughness `× (1.2 − 0.2 √cos θ_o)` in sampling and
/// in the density: the twin samples' density without it (the lobe's own roughness).
#[test]
fn beckmann_all_normals_from_outside() {
    let m = glass(Distribution::Beckmann, (0.25, 0.25), false, 1.5);
    let g = Glass::new(m.clone(), theta(60.0), false);
    let wrong = [
        ("alpha 3 % wide", scaled(&m, 1.03)),
        (
            "visible-normal sampling",
            glass(Distribution::Beckmann, (0.25, 0.25), true, 1.5),
        ),
    ];
    check(
        "Beckmann α 0.25 η 1.5 all normals, outside at 60°",
        &g,
        0.25,
        204,
        &wrong,
    );
}

/// The whole distribution from inside, beyond the critical angle at the macrosurface (55°):
/// only normals tilted towards `wo` refract.
#[test]
fn ggx_all_normals_from_inside_beyond_the_critical_angle() {
    let m = glass(Distribution::Ggx, (0.35, 0.35), false, 1.5);
    let g = Glass::new(m.clone(), theta(55.0), true);
    let wrong = [("alpha 3 % narrow", scaled(&m, 0.97))];
    check(
        "GGX α 0.35 η 1/1.5 all normals, inside at 55°",
        &g,
        0.35,
        205,
        &wrong,
    );
}

/// `∫ f |cos| dω` over the sphere by a midpoint rule in (cos θ, φ) about the normal, each
/// hemisphere apart.
fn albedo_by_quadrature(g: &Glass, f: impl Fn(DVec3) -> f64) -> f64 {
    let (nt, np) = (2000, 2000);
    let mut sum = 0.0;
    for side in [1.0, -1.0] {
        for i in 0..nt {
            let c = (i as f64 + 0.5) / nt as f64;
            let s = (1.0 - c * c).sqrt();
            for j in 0..np {
                let phi = 2.0 * PI * (j as f64 + 0.5) / np as f64;
                let d = g.world(DVec3::new(s * phi.cos(), s * phi.sin(), side * c));
                sum += f(d) * c;
            }
        }
    }
    sum * 2.0 * PI / (nt * np) as f64
}

/// The lobe's value written out again (white, radiance scaling undone: importance
/// transport, `η²` times the radiance-mode refraction), with knobs to break it: masking
/// dropped (`G = 1`), and the refraction's Jacobian `η² |wi·h| / (wo·h + η wi·h)²`
/// replaced by the reflection's `1 / (4 |wi·h|)`.
fn importance_value(g: &Glass, world: DVec3, masking: bool, refraction_jacobian: bool) -> f64 {
    let (wo, wi) = (g.local(g.wo.as_dvec3().normalize()), g.local(world));
    let d = lobe(&g.m).microfacet;
    let eta = g.eta();
    if wi.z == 0.0 {
        return 0.0;
    }
    let reflect = wi.z > 0.0;
    let h = if reflect { wo + wi } else { wo + wi * eta }.normalize();
    let h = if h.z < 0.0 { -h } else { h };
    let (cos_o, cos_i) = (wo.dot(h), wi.dot(h));
    if !(cos_o > 0.0 && cos_i * wi.z > 0.0) {
        return 0.0;
    }
    let gg = if masking { d.g(wo, wi, h) } else { 1.0 };
    let f = fresnel_dielectric(cos_o, eta).0;
    let dh = d.d(h);
    if reflect {
        return f * dh * gg / (4.0 * wo.z * wi.z);
    }
    let jacobian = if refraction_jacobian {
        let denom = cos_o + eta * cos_i;
        eta * eta * cos_i.abs() / (denom * denom)
    } else {
        1.0 / (4.0 * cos_i.abs())
    };
    // f_t = (1 − F) D G |wo·h| · jacobian / (|cos θ_o| |cos θ_i|), importance mode.
    (1.0 - f) * dh * gg * cos_o * jacobian / (wo.z * wi.z.abs())
}

/// White furnace of a rough dielectric that reflects and transmits everything: with the
/// radiance scaling of refraction undone (importance transport, which conserves energy),
/// reflection plus transmission is at most 1 and loses only what masking loses. The mean
/// sampled weight (by the BSDF's own sampling, each refracted sample's `1/η²` undone as
/// `pt`'s roulette undoes it) agrees with the quadrature of `eval` over the sphere (the same
/// undone), and with the value written out again; the albedo without masking (`G = 1`) and
/// the one whose refraction has the reflection's Jacobian must be rejected. From outside
/// and from inside, GGX exactly, Beckmann to `G1`'s rational fit (as in Mitsuba: see the
/// conductor's furnace).
#[test]
fn white_furnace_conserves_energy_and_loses_only_what_masking_loses() {
    const Z: f64 = 4.0;
    for (distribution, alpha, deg, back, seed) in [
        (Distribution::Ggx, (0.5, 0.5), 60.0, false, 1u64),
        (Distribution::Ggx, (0.3, 0.3), 30.0, true, 2),
        (Distribution::Beckmann, (0.4, 0.4), 45.0, false, 3),
        (Distribution::Ggx, (0.15, 0.5), 50.0, true, 4),
    ] {
        let m = glass(distribution, alpha, true, 1.5);
        let g = Glass::new(m.clone(), theta(deg), back);
        let count = 1_000_000u64;
        let (mut sum, mut sum2) = (0.0, 0.0);
        let mut rng = sample_rng(seed, 0, 0);
        let ns = if back { -g.frame.n } else { g.frame.n };
        for _ in 0..count {
            let u = [0; 3].map(|_| f64::from(uniform(&mut rng)));
            let w = bsdf::sample(&g.m, g.frame, g.wo, u).map_or(0.0, |s| {
                let undo = genpath::scene::material::specular::radiance_scale(&g.m, ns, g.wo, s.wi);
                f64::from(s.weight.x / undo)
            });
            sum += w;
            sum2 += w * w;
        }
        let mean = sum / count as f64;
        let se = ((sum2 / count as f64 - mean * mean) / count as f64).sqrt();
        let eta = g.eta();
        let quadrature = albedo_by_quadrature(&g, |d| {
            let f = f64::from(bsdf::eval(&g.m, g.frame, g.wo, d.as_vec3()).x);
            if d.dot(g.nd()) < 0.0 {
                f * eta * eta
            } else {
                f
            }
        });
        let model = albedo_by_quadrature(&g, |d| importance_value(&g, d, true, true));
        let unmasked = albedo_by_quadrature(&g, |d| importance_value(&g, d, false, true));
        let no_jacobian = albedo_by_quadrature(&g, |d| importance_value(&g, d, true, false));
        let z = |a: f64| (mean - a) / se;
        println!(
            "furnace {distribution:?} α {alpha:?} at {deg}° {}: sampled {mean:.5} ± {se:.1e}, quadrature {quadrature:.5} (z {:.2}), model {model:.5}, without masking {unmasked:.5} (z {:.1}), with the reflection's Jacobian {no_jacobian:.5} (z {:.1})",
            if back { "inside" } else { "outside" },
            z(quadrature),
            z(unmasked),
            z(no_jacobian),
        );
        assert!(
            (quadrature - model).abs() < 1e-3 * model,
            "eval {quadrature} against the model {model}"
        );
        match distribution {
            Distribution::Ggx => assert!(z(quadrature).abs() < Z, "furnace disagrees"),
            Distribution::Beckmann => {
                let rel = (mean / quadrature - 1.0).abs();
                assert!(rel < 0.0035, "furnace disagrees beyond G1's fit: {rel}");
            }
        }
        assert!(mean <= 1.0 && quadrature <= 1.0, "{mean} {quadrature}");
        for (what, albedo) in [
            ("without masking", unmasked),
            ("with the reflection's Jacobian", no_jacobian),
        ] {
            assert!(
                z(albedo).abs() > Z,
                "the albedo {what} was not rejected: z {}",
                z(albedo)
            );
        }
    }
}

/// Radiance-mode transmission is reciprocal up to the indices: `f(wi, wo) = η² f(wo, wi)`
/// for `η` the index `wo` meets (the BSDF seen from `wi`'s side meets `1/η`), and
/// reflection is symmetric, on both sides.
#[test]
fn transmission_is_reciprocal_up_to_eta_squared() {
    let m = glass(Distribution::Ggx, (0.2, 0.45), true, 1.5);
    let mut rng = sample_rng(19, 0, 0);
    let n = normal();
    let s = frame(n.as_dvec3()).0.as_vec3();
    for i in 0..20_000 {
        let mut dir = |side: f64| {
            let (a, b) = (f64::from(uniform(&mut rng)), f64::from(uniform(&mut rng)));
            about(n.as_dvec3() * side, (a * 0.999).acos(), 2.0 * PI * b).as_vec3()
        };
        // `a` outside (on the stored normal's side), `b` on either side.
        let side = if i % 2 == 0 { 1.0 } else { -1.0 };
        let (a, b) = (dir(1.0), dir(side));
        let from_a = bsdf::eval(&m, Frame::new(n, s), a, b);
        let from_b = if side > 0.0 {
            bsdf::eval(&m, Frame::new(n, s), b, a)
        } else {
            bsdf::eval(&m, Frame::behind(-n, s), b, a)
        };
        let eta2 = if side > 0.0 { 1.0 } else { 1.5f32 * 1.5 };
        let want = from_a * eta2;
        assert!(
            (from_b - want).abs().max_element() <= 2e-5 * want.max_element().max(1e-3),
            "{from_b} {want} ({side})"
        );
    }
}

/// One row of Mitsuba's table: `si.wi`, `wo` (genpath's `wo`, `wi`), `f` without the
/// cosine, the density.
type Row = ([f32; 3], [f32; 3], [f64; 3], f64);

/// The materials and rows of `roughdielectric_mitsuba.txt`.
fn mitsuba_table() -> Vec<(String, Material, Vec<Row>)> {
    let mut out: Vec<(String, Material, Vec<Row>)> = Vec::new();
    for line in include_str!("roughdielectric_mitsuba.txt").lines() {
        if line.starts_with('#') || line.trim().is_empty() {
            continue;
        }
        let fields: Vec<&str> = line.split_whitespace().collect();
        if fields[0] == "material" {
            let f = |i: usize| fields[i].parse::<f64>().unwrap();
            let distribution = match fields[2] {
                "ggx" => Distribution::Ggx,
                "beckmann" => Distribution::Beckmann,
                other => panic!("{other}"),
            };
            let rgb = |i: usize| Vec3::new(f(i) as f32, f(i + 1) as f32, f(i + 2) as f32);
            let m = tinted(
                distribution,
                (f(3), f(4)),
                fields[5] == "true",
                fields[6].parse::<f32>().unwrap(),
                (rgb(7), rgb(10)),
            );
            out.push((fields[1].to_string(), m, Vec::new()));
            continue;
        }
        let last = out.last_mut().expect("a material line first");
        assert_eq!(fields[0], last.0);
        let v = |i: usize| fields[i].parse::<f64>().unwrap();
        let v32 = |i: usize| fields[i].parse::<f32>().unwrap();
        last.2.push((
            [v32(1), v32(2), v32(3)],
            [v32(4), v32(5), v32(6)],
            [v(7), v(8), v(9)],
            v(10),
        ));
    }
    out
}

/// `eval` (without the cosine) and `pdf` against Mitsuba 3.9.1's `scalar_rgb`, at pairs of
/// its local frame's directions: from outside (`Frame::new(z, x)`: genpath's local frame is
/// Mitsuba's) and from inside (`si.wi` below: `Frame::behind(−z, x)`, whose `n` faces `wo`,
/// so that the lobe meets the index `1/η` and its local frame is Mitsuba's turned about
/// `x`); reflection, transmission, total internal reflection and zeros, to 1e-5.
#[test]
fn eval_and_pdf_are_mitsubas() {
    let table = mitsuba_table();
    assert_eq!(table.len(), 5);
    let (mut rows, mut zeros, mut worst) = (0, 0, 0.0f64);
    for (name, m, cases) in &table {
        for (wo, wi, f, pdf) in cases {
            let (wo, wi) = (Vec3::from(*wo), Vec3::from(*wi));
            let frame = if wo.z >= 0.0 {
                Frame::new(Vec3::Z, Vec3::X)
            } else {
                Frame::behind(-Vec3::Z, Vec3::X)
            };
            let got = bsdf::eval(m, frame, wo, wi).as_dvec3();
            let got_pdf = bsdf::pdf(m, frame, wo, wi);
            let want = DVec3::from(*f);
            println!(
                "{name} {wo} {wi}: eval {got} against {want}, pdf {got_pdf:.7e} against {pdf:.7e}"
            );
            if want == DVec3::ZERO {
                assert!(
                    got == DVec3::ZERO && got_pdf == 0.0 && *pdf == 0.0,
                    "{name}: {got} {got_pdf}"
                );
                zeros += 1;
                continue;
            }
            let rel = ((got - want).abs() / want).max_element();
            let rel_pdf = (got_pdf - pdf).abs() / pdf;
            worst = worst.max(rel).max(rel_pdf);
            assert!(
                rel < 1e-5,
                "{name}: eval {got} against Mitsuba's {want} ({rel:.1e})"
            );
            assert!(
                rel_pdf < 1e-5,
                "{name}: pdf {got_pdf} against Mitsuba's {pdf} ({rel_pdf:.1e})"
            );
            rows += 1;
        }
    }
    println!("{rows} non-zero rows, worst relative difference {worst:.1e}; {zeros} zeros");
    assert!(rows >= 40 && zeros >= 5);
}
