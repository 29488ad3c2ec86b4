//! Mitsuba's smooth `plastic` (`genpath::scene::SmoothPlastic`): its lobe choice and diffuse
//! lobe against values printed by Mitsuba 3.9.1 itself (`plastic_mitsuba.txt`, by
//! `scripts/mitsuba_plastic_table.py`), through the choice a hit makes
//! (`Material::scattering_at`) and the one BSDF interface (`brdf`, `specular`); and χ² of
//! the diffuse choice's samples against its density, with the density of Mitsuba's unchosen
//! vertex (the diffuse lobe's times its probability) as the must-reject twin.

use super::*;
use genpath::scene::material::specular;
use genpath::scene::SmoothPlastic;

/// A one-sided smooth plastic.
fn plastic(eta: f32, diffuse: Vec3, specular: Vec3, nonlinear: bool) -> Material {
    Material {
        name: "plastic".into(),
        kd: Vec3::ZERO,
        ks: Vec3::ZERO,
        glossy: Glossy::Plastic(Box::new(SmoothPlastic::new(
            eta, diffuse, specular, nonlinear,
        ))),
        mirror: false,
        ke: Vec3::ZERO,
        two_sided: false,
        conductor: None,
        dielectric: None,
        textures: None,
    }
}

/// The materials and rows of `plastic_mitsuba.txt`: per row the material, `wo` and `wi`
/// (Mitsuba's `si.wi` and `wo`) in the local frame, `f` (RGB, no cosine), the density,
/// the delta choice's probability and its weight (RGB).
type Row = (Material, DVec3, DVec3, DVec3, f64, f64, DVec3);

fn table() -> Vec<Row> {
    let mut materials = std::collections::HashMap::new();
    let mut rows = Vec::new();
    for line in include_str!("plastic_mitsuba.txt").lines() {
        if line.starts_with('#') {
            continue;
        }
        let w: Vec<&str> = line.split_whitespace().collect();
        let num = |i: usize| w[i].parse::<f64>().unwrap();
        let vec = |i: usize| DVec3::new(num(i), num(i + 1), num(i + 2));
        if w[0] == "material" {
            let m = plastic(
                num(2) as f32,
                vec(4).as_vec3(),
                vec(7).as_vec3(),
                w[3] == "true",
            );
            materials.insert(w[1].to_string(), m);
            continue;
        }
        let m = materials[w[0]].clone();
        rows.push((m, vec(1), vec(4), vec(7), num(10), num(11), vec(12)));
    }
    assert!(rows.len() >= 20, "{} rows", rows.len());
    rows
}

fn close(a: f64, b: f64, what: &str) {
    assert!(
        (a - b).abs() <= 2e-6 * b.abs().max(1e-3),
        "{what}: genpath {a}, Mitsuba {b}"
    );
}

/// Mitsuba's `eval`, `pdf`, `prob_specular` and the delta's sampled weight, as genpath
/// makes them from a hit's choice: `bsdf::eval` and `bsdf::pdf` of the diffuse choice times
/// its probability, the choice of the delta for a uniform number just below `P_s` and of
/// the diffuse lobe just above it, and the delta's `specular::sample` weight.
#[test]
fn plastic_matches_mitsubas_values() {
    let frame = Frame::new(Vec3::Z, Vec3::X);
    let mut worst = 0.0f64;
    for (m, wo, wi, f, pdf, p_specular, weight) in table() {
        let (wo32, wi32) = (wo.as_vec3(), wi.as_vec3());
        let cos_o = wo32.z;
        let Glossy::Plastic(lobe) = &m.glossy else {
            unreachable!()
        };
        let p = lobe.specular_probability(f64::from(cos_o));
        close(p, p_specular, "P_s");
        let below = m.scattering_at(glam::Vec2::ZERO, cos_o, (p * (1.0 - 1e-6)) as f32);
        let above = m.scattering_at(glam::Vec2::ZERO, cos_o, (p * (1.0 + 1e-6)) as f32);
        assert!(below.mirror && !above.mirror);
        let s = specular::sample(below, Vec3::Z, wo32, 0.0).unwrap();
        assert!(s.delta && (s.wi - Vec3::new(-wo32.x, -wo32.y, wo32.z)).length() < 1e-6);
        let ours_f = bsdf::eval(above, frame, wo32, wi32).as_dvec3() * (1.0 - p);
        let ours_pdf = bsdf::pdf(above, frame, wo32, wi32) * (1.0 - p);
        for c in 0..3 {
            close(f64::from(s.weight[c]), weight[c], "delta weight");
            close(ours_f[c], f[c], "f");
            worst = worst.max((ours_f[c] - f[c]).abs() / f[c].abs().max(1e-3));
        }
        close(ours_pdf, pdf, "pdf");
    }
    println!("plastic against Mitsuba: worst relative difference of f {worst:.2e}");
}

/// The diffuse choice samples its cosine density, as `bsdf::pdf` says, at normal and grazing
/// incidence; the density of Mitsuba's vertex before the choice (the cosine times the
/// diffuse lobe's probability, which a method taking the choice at the hit must leave out)
/// is rejected by the same histograms.
#[test]
fn brdf_plastic_diffuse_choice() {
    for (theta_o, seed) in [(0.3, 61), (GRAZING, 62)] {
        let m = plastic(1.6, Vec3::new(0.7, 0.4, 0.2), Vec3::ONE, false);
        let v = Vertex::new(m, theta_o);
        let name = format!("plastic's diffuse choice at θ_o {theta_o:.2}");
        let (outcomes, hist) = check_brdf(&name, &v, SphereBins::equal_area(v.nd(), 16, 32), seed);
        assert_eq!(hist.counts[outcomes.above.bins()], 0, "rejections");
        let Glossy::Plastic(lobe) = &v.m.glossy else {
            unreachable!()
        };
        let p_diffuse = 1.0 - lobe.specular_probability(v.nd().dot(v.wo.as_dvec3()));
        FAMILY.reject(
            &format!("{name} with the choice's probability in its density ({p_diffuse:.3})"),
            &chi2(&outcomes, &hist, on_outcomes(|d| p_diffuse * v.pdf(d))),
        );
    }
}
