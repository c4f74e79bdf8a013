//! The moments' fold against direct computation, in any order and across shards.

use super::*;

/// Values of any size give the statistics of the same values at ordinary size, scaled
/// exactly (bit for bit), with a σ interval; blocks of different scales combine.
#[test]
fn huge_and_tiny_values_give_the_statistics_of_ordinary_ones_scaled() {
    let xs: Vec<f64> = (0..400)
        .map(|i| 1.0 + 0.01 * ((i * 7919) % 1000) as f64 / 100.0)
        .collect();
    let stat_of = |k: i32| {
        let mut m = Moments::default();
        xs.iter().for_each(|&x| m.add(times_two_to(x, k)));
        m.stat()
    };
    let plain = stat_of(0);
    for k in [490, 1000, -600, -1000] {
        let s = stat_of(k);
        let back = |x: f64| times_two_to(x, -k);
        assert_eq!(back(s.mean).to_bits(), plain.mean.to_bits(), "2^{k}");
        assert_eq!(back(s.std).to_bits(), plain.std.to_bits(), "2^{k}");
        assert_eq!(
            back(s.std_ci.0).to_bits(),
            plain.std_ci.0.to_bits(),
            "2^{k}"
        );
        assert_eq!(
            back(s.std_ci.1).to_bits(),
            plain.std_ci.1.to_bits(),
            "2^{k}"
        );
        assert_eq!(
            back(s.mean_ci.1).to_bits(),
            plain.mean_ci.1.to_bits(),
            "2^{k}"
        );
    }
    // Unscaled, 2^490's fourth moments overflow: the σ interval is none, not [σ, σ].
    let mut m = Moments::default();
    m.add(0.0);
    xs.iter().for_each(|&x| m.add(times_two_to(x, 490)));
    let s = m.stat();
    assert!(
        s.std.is_finite() && s.std_ci.0.is_nan() && s.std_ci.1.is_nan(),
        "{s:?}"
    );
    // A block of an ordinary value and one of a huge value combine at the larger scale.
    let mut c = Moments::default();
    c.add(1e300);
    let mut d = Moments::default();
    d.add(2.0);
    d.combine(&c);
    assert_eq!(d.scale, c.scale);
    let e = d.stat();
    assert!(
        (e.mean - 5e299).abs() < 1e285 && (e.std - 1e300 / 2f64.sqrt()).abs() < 1e286,
        "{e:?}"
    );
}

/// Moments that overflowed read back as they were written (bit for bit where finite).
#[test]
fn non_finite_moments_survive_a_shard_file() {
    let mut m = Moments::default();
    for x in [0.0, 8.7e146, -3.1e146, 1.25e147] {
        m.add(x);
    }
    assert!(!m.m4.is_finite() && m.mean.is_finite(), "{m:?}");
    (m.m2, m.m3, m.m4) = (f64::NEG_INFINITY, f64::NAN, f64::INFINITY);
    let text = serde_json::to_string(&m).unwrap();
    let back: Moments = serde_json::from_str(&text).unwrap();
    assert_eq!(back.mean.to_bits(), m.mean.to_bits());
    assert!(back.m4 == f64::INFINITY);
    assert!(back.m2 == f64::NEG_INFINITY);
    assert!(back.m3.is_nan());
    assert!(serde_json::from_str::<Moments>(&text.replace("\"NaN\"", "\"nan?\"")).is_err());
}

#[test]
fn streaming_moments_match_two_pass() {
    let xs: Vec<f64> = (0..1000)
        .map(|i| ((i * 7919) % 1000) as f64 / 100.0 + (i as f64 * 0.37).sin().powi(3))
        .collect();
    let mut w = Moments::default();
    xs.iter().for_each(|&x| w.add(x));
    let n = xs.len() as f64;
    let mean = xs.iter().sum::<f64>() / n;
    let m2: f64 = xs.iter().map(|x| (x - mean).powi(2)).sum();
    let m3: f64 = xs.iter().map(|x| (x - mean).powi(3)).sum();
    let m4: f64 = xs.iter().map(|x| (x - mean).powi(4)).sum();
    assert!((w.mean - mean).abs() < 1e-12 * mean.abs());
    assert!((w.m2 - m2).abs() < 1e-10 * m2);
    assert!((w.m3 - m3).abs() < 1e-8 * m3.abs().max(m2));
    assert!((w.m4 - m4).abs() < 1e-10 * m4);
    // Combining two halves gives the moments of the whole.
    let (mut a, mut b) = (Moments::default(), Moments::default());
    xs[..377].iter().for_each(|&x| a.add(x));
    xs[377..].iter().for_each(|&x| b.add(x));
    a.combine(&b);
    assert_eq!(a.n, w.n);
    assert!((a.mean - w.mean).abs() < 1e-12 * w.mean.abs());
    assert!((a.m2 - w.m2).abs() < 1e-10 * w.m2);
    assert!((a.m3 - w.m3).abs() < 1e-8 * w.m3.abs().max(w.m2));
    assert!((a.m4 - w.m4).abs() < 1e-10 * w.m4);
    // Normal-like data: the σ interval is close to the χ² one, about ±1.96/√(2n).
    let s = w.stat();
    assert!(s.std_ci.0 < s.std && s.std < s.std_ci.1);
}
