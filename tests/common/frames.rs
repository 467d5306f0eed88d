//! Comparing rendered frames: depth agreement and colour/hit-mask agreement.

/// Fraction of pixels where both images agree on hit/miss and, on hits, on depth within
/// `tol`. `None` in the first image counts as a miss.
pub fn depth_agreement(a: &[f32], b: &[f32], tol: f32) -> (f64, usize) {
    let mut ok = 0;
    let mut hits = 0;
    for (x, y) in a.iter().zip(b) {
        hits += usize::from(x.is_finite() || y.is_finite());
        let same = match (x.is_finite(), y.is_finite()) {
            (true, true) => (x - y).abs() <= tol,
            (false, false) => true,
            _ => false,
        };
        ok += usize::from(same && (x.is_finite() || y.is_finite()));
    }
    (ok as f64 / hits.max(1) as f64, hits)
}

/// Asserts that two renders of the same scene agree: on ≥ 99 % of pixels every colour
/// channel within 6 levels, and on ≥ 99 % of pixels the same hit/miss.
pub fn assert_frames_match(name: &str, a: &karstic::render::Frame, b: &karstic::render::Frame) {
    assert_frames_match_within(name, a, b, 0.99);
}

/// [`assert_frames_match`] with the colours agreeing on a `share` of the pixels (the hit
/// masks still on 99 %).
pub fn assert_frames_match_within(
    name: &str,
    a: &karstic::render::Frame,
    b: &karstic::render::Frame,
    share: f64,
) {
    let n = a.depth.len();
    assert_eq!(n, b.depth.len(), "{name}: frame sizes differ");
    let close = (0..n)
        .filter(|&k| (0..3).all(|c| a.rgba[4 * k + c].abs_diff(b.rgba[4 * k + c]) <= 6))
        .count();
    let hits_agree = (0..n)
        .filter(|&k| a.depth[k].is_finite() == b.depth[k].is_finite())
        .count();
    assert!(
        close as f64 >= share * n as f64,
        "{name}: {close} of {n} pixels match"
    );
    assert!(
        hits_agree as f64 >= 0.99 * n as f64,
        "{name}: hit masks differ on {} pixels",
        n - hits_agree
    );
}
