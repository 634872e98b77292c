//! Isotropic GGX (Trowbridge-Reitz) microfacet terms in f64, written in
//! terms of theta and the Smith Lambda function, independently of himal's
//! dot-product forms.

use std::f64::consts::PI;

fn tan2_of_cos(cos_theta: f64) -> f64 {
    let c2 = cos_theta * cos_theta;
    (1.0 - c2).max(0.0) / c2
}

/// Walter et al. 2007 eq. 33: D(m) = alpha^2 / (pi cos^4 (alpha^2 + tan^2)^2)
/// for cos(theta_m) > 0, else 0.
pub fn ggx_d(cos_theta_m: f64, alpha: f64) -> f64 {
    if cos_theta_m <= 0.0 {
        return 0.0;
    }
    let a2 = alpha * alpha;
    let c4 = cos_theta_m.powi(4);
    a2 / (PI * c4 * (a2 + tan2_of_cos(cos_theta_m)).powi(2))
}

/// Heitz 2014 eq. 72: Lambda = (-1 + sqrt(1 + alpha^2 tan^2 theta)) / 2.
pub fn ggx_lambda(cos_theta: f64, alpha: f64) -> f64 {
    0.5 * ((1.0 + alpha * alpha * tan2_of_cos(cos_theta)).sqrt() - 1.0)
}

/// Smith masking G1 = 1 / (1 + Lambda).
pub fn ggx_g1(cos_theta: f64, alpha: f64) -> f64 {
    1.0 / (1.0 + ggx_lambda(cos_theta, alpha))
}

/// Height-correlated masking-shadowing G2 = 1 / (1 + Lambda_o + Lambda_i)
/// (Heitz 2014 eq. 99), both directions above the surface.
pub fn ggx_g2_height_correlated(cos_o: f64, cos_i: f64, alpha: f64) -> f64 {
    1.0 / (1.0 + ggx_lambda(cos_o, alpha) + ggx_lambda(cos_i, alpha))
}

/// Visibility V = G2 / (4 cos_o cos_i).
pub fn ggx_v_height_correlated(cos_o: f64, cos_i: f64, alpha: f64) -> f64 {
    ggx_g2_height_correlated(cos_o, cos_i, alpha) / (4.0 * cos_o * cos_i)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn known_values() {
        // D at the peak is 1 / (pi alpha^2); alpha = 1 is uniform: 1/pi.
        assert!((ggx_d(1.0, 0.5) - 1.0 / (PI * 0.25)).abs() < 1e-12);
        assert!((ggx_d(0.3, 1.0) - 1.0 / PI).abs() < 1e-12);
        // No masking at normal incidence; G1 at 60 deg, alpha 1: 1/(1+(sqrt(4)-1)/2).
        assert_eq!(ggx_g1(1.0, 0.7), 1.0);
        assert!((ggx_g1(0.5, 1.0) - 1.0 / 1.5).abs() < 1e-12);
    }
}
