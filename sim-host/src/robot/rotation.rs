//! Rotations as unit quaternions `[w, x, y, z]` (MuJoCo's order), for the torso's ground truth
//! and the transforms the Foxglove log carries.

/// Roll, pitch, yaw (Z-Y-X Euler angles: URDF's `R = Rz(yaw) Ry(pitch) Rx(roll)`), rad, of the
/// unit quaternion `q`. Pitch + = nose down (a rotation about +y).
pub fn rpy_rad([w, x, y, z]: [f64; 4]) -> [f64; 3] {
    let roll = (2.0 * (w * x + y * z)).atan2(1.0 - 2.0 * (x * x + y * y));
    let pitch = (2.0 * (w * y - z * x)).clamp(-1.0, 1.0).asin();
    let yaw = (2.0 * (w * z + x * y)).atan2(1.0 - 2.0 * (y * y + z * z));
    [roll, pitch, yaw]
}

/// The inverse of a unit quaternion.
pub fn conjugate([w, x, y, z]: [f64; 4]) -> [f64; 4] {
    [w, -x, -y, -z]
}

/// The Hamilton product `a ⊗ b`: `b`'s rotation, then `a`'s.
pub fn multiply(a: [f64; 4], b: [f64; 4]) -> [f64; 4] {
    let [aw, ax, ay, az] = a;
    let [bw, bx, by, bz] = b;
    [
        aw * bw - ax * bx - ay * by - az * bz,
        aw * bx + ax * bw + ay * bz - az * by,
        aw * by - ax * bz + ay * bw + az * bx,
        aw * bz + ax * by - ay * bx + az * bw,
    ]
}

/// `v` rotated by the unit quaternion `q` (a vector of `q`'s frame in its parent's).
pub fn rotate(q: [f64; 4], v: [f64; 3]) -> [f64; 3] {
    let [w, x, y, z] = q;
    let u = [x, y, z];
    let t = cross(u, v).map(|c| 2.0 * c);
    let ut = cross(u, t);
    [0, 1, 2].map(|i| v[i] + w * t[i] + ut[i])
}

/// The cross product `a × b`.
pub fn cross(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_quarter_turn_about_z_takes_x_to_y_and_reads_as_yaw() {
        let half = std::f64::consts::FRAC_PI_4;
        let q = [half.cos(), 0.0, 0.0, half.sin()];
        let v = rotate(q, [1.0, 0.0, 0.0]);
        assert!(v[0].abs() < 1e-12 && (v[1] - 1.0).abs() < 1e-12);
        let back = rotate(conjugate(q), v);
        assert!((back[0] - 1.0).abs() < 1e-12 && back[1].abs() < 1e-12);
        let twice = multiply(q, q);
        assert!((rpy_rad(twice)[2] - std::f64::consts::PI).abs() < 1e-12);
        let [roll, pitch, yaw] = rpy_rad(q);
        assert!(roll.abs() < 1e-12 && pitch.abs() < 1e-12);
        assert!((yaw - std::f64::consts::FRAC_PI_2).abs() < 1e-12);
    }
}
