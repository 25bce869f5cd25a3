//! Local contact frames (eq. 11): the unit normal `n` first, then the tangents, an
//! orthonormal basis. In 2-D the tangent is `n` turned by +90°; in 3-D the first
//! tangent is `n × e` normalized, with `e` the coordinate axis least aligned with `n`
//! (so the construction never divides by a small number), and the second is `n × t₁`.
//! The frame of a fixed plane is constant, so the tangential Jacobian rows stay
//! constant too; on a curved obstacle it turns with the normal.

/// The tangents of the unit normal `n` (length 2 or 3): one in 2-D, two in 3-D (the
/// unused slot is zero).
pub fn tangents(n: &[f64]) -> [[f64; 3]; 2] {
    match n.len() {
        2 => [[-n[1], n[0], 0.0], [0.0; 3]],
        3 => {
            let k = (0..3)
                .min_by(|&a, &b| n[a].abs().total_cmp(&n[b].abs()))
                .expect("three components");
            let nv = nalgebra::Vector3::new(n[0], n[1], n[2]);
            let t1 = nv.cross(&nalgebra::Vector3::ith(k, 1.0)).normalize();
            let t2 = nv.cross(&t1);
            [t1.into(), t2.into()]
        }
        _ => [[0.0; 3]; 2],
    }
}

/// Writes the block of a nodal contact with unit normal `n` into the `d` columns of
/// `jac` starting at `row` (normal, then the first `d − 1` tangents); each column holds
/// the node's `n.len()` dofs.
pub fn write_nodal_block(n: &[f64], d: usize, row: usize, jac: &mut super::ContactJacobian) {
    jac.col_values_mut(row).copy_from_slice(n);
    if d > 1 {
        let t = tangents(n);
        for (c, tc) in t.iter().enumerate().take(d - 1) {
            jac.col_values_mut(row + 1 + c)
                .copy_from_slice(&tc[..n.len()]);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The frames are orthonormal, right-handed in 3-D, for normals along and between
    /// the axes.
    #[test]
    fn frames_are_orthonormal() {
        let s = 1.0 / 3f64.sqrt();
        for n in [
            [0.0, 0.0, 1.0],
            [1.0, 0.0, 0.0],
            [s, s, s],
            [0.6, -0.8, 0.0],
        ] {
            let [t1, t2] = tangents(&n);
            let dot = |a: &[f64], b: &[f64]| a.iter().zip(b).map(|(x, y)| x * y).sum::<f64>();
            for (a, b, want) in [
                (&n[..], &t1[..], 0.0),
                (&n[..], &t2[..], 0.0),
                (&t1[..], &t2[..], 0.0),
                (&t1[..], &t1[..], 1.0),
                (&t2[..], &t2[..], 1.0),
            ] {
                assert!((dot(a, b) - want).abs() < 1e-15);
            }
            let c: [f64; 3] = nalgebra::Vector3::from(t1)
                .cross(&nalgebra::Vector3::from(t2))
                .into();
            assert!((dot(&c, &n) - 1.0).abs() < 1e-15, "right-handed");
        }
        let [t, _] = tangents(&[0.0, 1.0]);
        assert_eq!(t, [-1.0, 0.0, 0.0]);
    }
}
