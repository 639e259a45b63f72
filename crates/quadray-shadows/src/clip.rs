//! Polygon clipping against axis planes: exact registration of polygons in the grid's cells.

use glam::Vec3;

/// Keeps the part of a convex polygon with `p[axis] >= lo` (`keep_above`) or `p[axis] <= lo`.
pub fn clip_axis(poly: &[Vec3], axis: usize, lo: f32, keep_above: bool, out: &mut Vec<Vec3>) {
    out.clear();
    let side = |p: Vec3| {
        if keep_above {
            p[axis] - lo
        } else {
            lo - p[axis]
        }
    };
    for i in 0..poly.len() {
        let (a, b) = (poly[i], poly[(i + 1) % poly.len()]);
        let (sa, sb) = (side(a), side(b));
        if sa >= 0.0 {
            out.push(a);
        }
        if (sa >= 0.0) != (sb >= 0.0) {
            let t = sa / (sa - sb);
            let mut p = a + (b - a) * t;
            p[axis] = lo; // exactly on the clip plane, whatever the rounding
            out.push(p);
        }
    }
}

/// Keeps the part of a convex polygon inside the slab `lo <= p[axis] <= hi`.
pub fn clip_slab(
    poly: &[Vec3],
    axis: usize,
    lo: f32,
    hi: f32,
    tmp: &mut Vec<Vec3>,
    out: &mut Vec<Vec3>,
) {
    clip_axis(poly, axis, lo, true, tmp);
    clip_axis(tmp, axis, hi, false, out);
}

#[cfg(test)]
mod tests {
    use super::*;
    use quadray_core::geom::Aabb;

    #[test]
    fn slab_clip_keeps_the_inside() {
        let tri = [
            Vec3::ZERO,
            Vec3::new(4.0, 0.0, 0.0),
            Vec3::new(0.0, 4.0, 0.0),
        ];
        let (mut a, mut b) = (Vec::new(), Vec::new());
        clip_slab(&tri, 0, 1.0, 2.0, &mut a, &mut b);
        let bx = Aabb::of_points(b.iter().copied());
        assert_eq!(
            (bx.min.x, bx.max.x, bx.min.y, bx.max.y),
            (1.0, 2.0, 0.0, 3.0)
        );
    }
}
