//! Sine, cosine and arctangent for arc planning, in a few hundred bytes of flash.
//!
//! Who uses it: [`crate::planning::arc`] (angles within a few turns). `libm`'s versions handle any
//! argument with a Payne–Hanek reduction and its 3 KB table; an arc's angles stay within
//! ±2π plus a little, where a two-part π/2 reduction is exact to the last bit or two and
//! Taylor series on ±π/4 (sine, cosine) or ±tan(π/12) (arctangent) converge below an
//! `f32` ulp. In `f32`, as Grbl's arcs: within 1.5e-7 of the exact values (`libm`'s `f64`)
//! over ±8 rad (unit tests), about one `f32` ulp of 1.

use core::f32::consts::{FRAC_PI_2, FRAC_PI_6, PI};

/// π/2 in two parts (the high part has 17 significant bits, so k·HI is exact for |k| < 128).
const PIO2_HI: f32 = 1.570_785_522_460_937_5;
const PIO2_LO: f32 = 1.080_433_412_4e-5;

/// (sin x, cos x) for |x| up to a few turns.
pub fn sin_cos(x: f32) -> (f32, f32) {
    let k = libm::roundf(x / FRAC_PI_2);
    let r = (x - k * PIO2_HI) - k * PIO2_LO;
    let r2 = r * r;
    // Horner over 1/n!: sin to r^13, cos to r^12 (|r| ≤ π/4: the next term is below 1e-11).
    let (mut s, mut c) = (0.0, 0.0);
    for n in (1..=6).rev() {
        s = 1.0 - r2 * s / ((2 * n) * (2 * n + 1)) as f32;
        c = 1.0 - r2 * c / ((2 * n - 1) * (2 * n)) as f32;
    }
    let s = r * s;
    // (Through i32, not i64, which links ~140 bytes of f32-to-i64 conversion: the same
    // quadrant for every |k| below 2^31, far beyond the few turns this is for.)
    match crate::num::i32_of(k).rem_euclid(4) {
        0 => (s, c),
        1 => (c, -s),
        2 => (-s, -c),
        _ => (-c, s),
    }
}

/// atan2(y, x) in (-π, π], as `libm::atan2f` for finite arguments.
pub fn atan2(y: f32, x: f32) -> f32 {
    let (ax, ay) = (libm::fabsf(x), libm::fabsf(y));
    if ax == 0.0 && ay == 0.0 {
        return if x.is_sign_negative() { PI.copysign(y) } else { 0.0f32.copysign(y) };
    }
    // atan of the ratio below 1, then the octant.
    let (t, swap) = if ay > ax { (ax / ay, true) } else { (ay / ax, false) };
    let mut a = atan_unit(t);
    if swap {
        a = FRAC_PI_2 - a;
    }
    if x < 0.0 {
        a = PI - a;
    }
    a.copysign(y)
}

/// atan t for 0 ≤ t ≤ 1.
fn atan_unit(t: f32) -> f32 {
    // tan(π/12) = 2 - √3: above it, atan t = π/6 + atan((t√3 - 1)/(t + √3)).
    const SQRT3: f32 = 1.732_050_8;
    let (base, u) = if t > 0.267_949_2 { (FRAC_PI_6, (t * SQRT3 - 1.0) / (t + SQRT3)) } else { (0.0, t) };
    let u2 = u * u;
    // Σ (-1)^n u^(2n+1)/(2n+1) to n = 7 (|u| ≤ 0.268: the next term is below 1e-10).
    let mut s = 0.0;
    for n in (0..=7).rev() {
        s = 1.0 / (2 * n + 1) as f32 - u2 * s;
    }
    base + u * s
}

#[cfg(test)]
mod tests {
    use super::*;

    // Tolerances: 2e-16 and 5e-16 when this ran in f64; in f32 (as Grbl's arcs) one ulp of
    // 1 is 1.2e-7, and arcs place points to within 1e-7 of their radius (1e-4 mm at 1 m).
    #[test]
    fn sin_cos_and_atan2_match_libm() {
        let mut worst = 0.0f64;
        for i in -80_000..=80_000 {
            let x = i as f32 * 1e-4 + 1e-9 * (i % 7) as f32;
            let (s, c) = sin_cos(x);
            let (es, ec) = (libm::sin(x as f64), libm::cos(x as f64));
            worst = worst.max((s as f64 - es).abs()).max((c as f64 - ec).abs());
        }
        assert!(worst < 1.5e-7, "sin/cos off by {worst}");
        let mut worst = 0.0f64;
        for i in -300..=300 {
            for j in -300..=300 {
                let (y, x) = (i as f32 * 0.37 + 1e-3, j as f32 * 0.41 - 2e-3);
                worst = worst.max((atan2(y, x) as f64 - libm::atan2(y as f64, x as f64)).abs());
            }
        }
        assert!(worst < 5e-7, "atan2 off by {worst}");
        for (y, x) in [(0.0, 1.0), (0.0, -1.0), (-0.0, -1.0), (1.0, 0.0), (-1.0, 0.0), (0.0, 0.0), (1e-30, -1.0)] {
            assert_eq!(atan2(y, x), libm::atan2f(y, x), "atan2({y}, {x})");
        }
    }
}
