//! The few three-vector operations the attitude filter needs, on `[f32; 3]`.

use crate::math::sqrt;

/// `a · b`.
pub(super) fn dot(a: [f32; 3], b: [f32; 3]) -> f32 {
    let ([ax, ay, az], [bx, by, bz]) = (a, b);
    ax * bx + ay * by + az * bz
}

/// `a × b`.
pub(super) fn cross(a: [f32; 3], b: [f32; 3]) -> [f32; 3] {
    let ([ax, ay, az], [bx, by, bz]) = (a, b);
    [ay * bz - az * by, az * bx - ax * bz, ax * by - ay * bx]
}

/// `k a`.
pub(super) fn scale(a: [f32; 3], k: f32) -> [f32; 3] {
    a.map(|x| x * k)
}

/// `f` on each pair of components.
pub(super) fn zip3(a: [f32; 3], b: [f32; 3], f: impl Fn(f32, f32) -> f32) -> [f32; 3] {
    let ([a0, a1, a2], [b0, b1, b2]) = (a, b);
    [f(a0, b0), f(a1, b1), f(a2, b2)]
}

/// `a` scaled to unit length; `None` for a zero or non-finite vector.
pub(super) fn normalise(a: [f32; 3]) -> Option<[f32; 3]> {
    let norm = sqrt(dot(a, a));
    (norm.is_finite() && norm > 1e-6).then(|| scale(a, 1.0 / norm))
}
