//! Perfect specular optics for the Whitted integrator: mirror reflection,
//! Snell refraction and the Fresnel equations (Whitted (1980), on the GPU after Purcell et al. (2002) trace
//! reflection and refraction rays this way).

use raykit_core::glam::Vec3;

/// Mirror `d` about the unit normal `n`: `d − 2 (d·n) n`.
pub fn reflect(d: Vec3, n: Vec3) -> Vec3 {
    d - 2.0 * d.dot(n) * n
}

/// Refract the unit direction `d` through a surface with unit normal `n`
/// facing the incoming side (`d·n < 0`), with `eta` = n_incident /
/// n_transmitted. `None` on total internal reflection.
pub fn refract(d: Vec3, n: Vec3, eta: f32) -> Option<Vec3> {
    let cos_i = (-d.dot(n)).clamp(0.0, 1.0);
    let sin2_t = eta * eta * (1.0 - cos_i * cos_i);
    if sin2_t > 1.0 {
        return None;
    }
    let cos_t = (1.0 - sin2_t).sqrt();
    Some((eta * d + (eta * cos_i - cos_t) * n).normalize())
}

/// Fresnel reflectance of unpolarised light at a dielectric boundary: the
/// mean of the s- and p-polarised reflectances for incidence cosine `cos_i`
/// and `eta` = n_incident / n_transmitted; 1 on total internal reflection.
pub fn fresnel_dielectric(cos_i: f32, eta: f32) -> f32 {
    let cos_i = cos_i.clamp(0.0, 1.0);
    let sin2_t = eta * eta * (1.0 - cos_i * cos_i);
    if sin2_t >= 1.0 {
        return 1.0;
    }
    let cos_t = (1.0 - sin2_t).sqrt();
    let rs = (eta * cos_i - cos_t) / (eta * cos_i + cos_t);
    let rp = (cos_i - eta * cos_t) / (cos_i + eta * cos_t);
    0.5 * (rs * rs + rp * rp)
}

/// Schlick's approximation for a conductor with normal-incidence
/// reflectance `f0` (per channel).
pub fn fresnel_schlick(cos_i: f32, f0: Vec3) -> Vec3 {
    let k = (1.0 - cos_i.clamp(0.0, 1.0)).powi(5);
    f0 + (Vec3::ONE - f0) * k
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Fresnel in f64 from the angles (Hecht's form), independent of the
    /// cosine form above.
    fn fresnel_f64(theta_i: f64, n1: f64, n2: f64) -> f64 {
        let s = n1 / n2 * theta_i.sin();
        if s >= 1.0 {
            return 1.0;
        }
        let theta_t = s.asin();
        if theta_i == 0.0 {
            let r = (n1 - n2) / (n1 + n2);
            return r * r;
        }
        let rs = (theta_i - theta_t).sin() / (theta_i + theta_t).sin();
        let rp = (theta_i - theta_t).tan() / (theta_i + theta_t).tan();
        0.5 * (rs * rs + rp * rp)
    }

    #[test]
    fn fresnel_matches_the_angle_form_in_f64() {
        for (n1, n2) in [(1.0, 1.5), (1.5, 1.0), (1.0, 2.4), (1.33, 1.0)] {
            for k in 0..=89 {
                let th = (k as f64).to_radians();
                let got = fresnel_dielectric(th.cos() as f32, (n1 / n2) as f32) as f64;
                let want = fresnel_f64(th, n1, n2);
                assert!(
                    (got - want).abs() < 2e-5,
                    "{n1}->{n2} at {k}°: {got} vs {want}"
                );
            }
        }
    }

    #[test]
    fn refraction_obeys_snell_and_total_internal_reflection() {
        let n = Vec3::Y;
        for k in 0..=85 {
            let th = (k as f64).to_radians();
            let d = Vec3::new(th.sin() as f32, -th.cos() as f32, 0.0);
            // Air into glass: n1 sin θi = n2 sin θt.
            let t = refract(d, n, 1.0 / 1.5).expect("no TIR entering glass");
            let sin_t = (t.x as f64).hypot(t.z as f64);
            assert!((th.sin() - 1.5 * sin_t).abs() < 1e-5, "{k}°");
            assert!(t.y < 0.0 && (t.length() - 1.0).abs() < 1e-5);
            // Glass into air: TIR beyond the critical angle asin(1/1.5).
            let out = refract(d, n, 1.5);
            let critical = (1.0f64 / 1.5).asin();
            assert_eq!(out.is_none(), th > critical + 1e-6, "{k}°");
        }
    }

    #[test]
    fn reflection_keeps_the_tangent_and_flips_the_normal_part() {
        let n = Vec3::new(1.0, 2.0, -0.5).normalize();
        let d = Vec3::new(0.3, -0.9, 0.2).normalize();
        let r = reflect(d, n);
        assert!((r.dot(n) + d.dot(n)).abs() < 1e-6);
        assert!(((r - r.dot(n) * n) - (d - d.dot(n) * n)).length() < 1e-6);
    }

    #[test]
    fn schlick_is_f0_at_normal_incidence_and_one_at_grazing() {
        let f0 = Vec3::new(0.9, 0.6, 0.2);
        assert!((fresnel_schlick(1.0, f0) - f0).length() < 1e-6);
        assert!((fresnel_schlick(0.0, f0) - Vec3::ONE).length() < 1e-6);
    }
}
