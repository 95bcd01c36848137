//! Units and angles, defined once: the speed of light, decibels, one angle-wrapping
//! convention and the two-way delay ↔ range relation.
//!
//! * Angles wrap into the half-open interval (−180°, 180°] ((−π, π] in radians): a bearing
//!   exactly behind is +180°, never −180°, so a wrapped angle has one representation.
//! * A monostatic echo's delay τ and the scatterer's range r are related by r = c₀·τ/2.
//! * Powers in dB are 10·log₁₀(x), floored at x = 1e−300 so that zero power reads −3000 dB
//!   (finite, sortable) instead of −∞.
//!
//! ```
//! use pradar_formats::units::{delay_ns, range_m, wrap_deg};
//! assert!((range_m(delay_ns(3.0)) - 3.0).abs() < 1e-12);
//! assert_eq!(wrap_deg(-180.0), 180.0);
//! ```

use std::f64::consts::PI;

/// Speed of light in vacuum (m/s).
pub const C0: f64 = 299_792_458.0;

/// Power ratio in dB: 10·log₁₀(x), floored at x = 1e−300.
pub fn db(x: f64) -> f64 {
    10.0 * x.max(1e-300).log10()
}

/// Wrap an angle in degrees into (−180, 180].
pub fn wrap_deg(a: f64) -> f64 {
    let r = a.rem_euclid(360.0);
    if r > 180.0 {
        r - 360.0
    } else {
        r
    }
}

/// Wrap an angle in radians into (−π, π].
pub fn wrap_rad(a: f64) -> f64 {
    let r = (a + PI).rem_euclid(2.0 * PI) - PI;
    if r <= -PI {
        r + 2.0 * PI
    } else {
        r
    }
}

/// Range (m) of a monostatic echo with round-trip delay `delay_ns`: r = c₀·τ/2.
pub fn range_m(delay_ns: f64) -> f64 {
    delay_ns * 1e-9 * C0 / 2.0
}

/// Round-trip delay (ns) of a monostatic echo from range `range_m`: τ = 2r/c₀.
pub fn delay_ns(range_m: f64) -> f64 {
    2.0 * range_m / C0 * 1e9
}

/// Range (m) of a monostatic echo with round-trip delay `delay_s` in seconds: r = c₀·τ/2.
pub fn range_from_delay_s(delay_s: f64) -> f64 {
    C0 * delay_s / 2.0
}

/// Round-trip delay (s) of a monostatic echo from range `range_m`: τ = 2r/c₀.
pub fn delay_s(range_m: f64) -> f64 {
    2.0 * range_m / C0
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    #[test]
    fn wrap_edges() {
        assert_eq!(wrap_deg(190.0), -170.0);
        assert_eq!(wrap_deg(-180.0), 180.0);
        assert_eq!(wrap_deg(180.0), 180.0);
        assert_eq!(wrap_deg(45.0), 45.0);
        assert_eq!(wrap_rad(-PI), PI);
        assert_eq!(wrap_rad(PI), PI);
    }

    #[test]
    fn db_of_zero_is_finite() {
        assert_eq!(db(100.0), 20.0);
        assert_eq!(db(0.0), -3000.0);
    }

    proptest! {
        #[test]
        fn wrap_is_in_range_and_congruent(a in -1e4f64..1e4) {
            let w = wrap_deg(a);
            prop_assert!(w > -180.0 && w <= 180.0);
            prop_assert!((((w - a) / 360.0).round() * 360.0 - (w - a)).abs() < 1e-9);
            let r = wrap_rad(a.to_radians());
            prop_assert!(r > -PI && r <= PI);
        }

        #[test]
        fn delay_range_round_trip(r in 0.0f64..1e4) {
            prop_assert!((range_m(delay_ns(r)) - r).abs() <= 1e-12 * r.max(1.0));
        }
    }
}
