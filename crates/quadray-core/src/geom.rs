//! The CPU ray tracing both techniques share: ray segments, boxes, convex planar polygons prepared
//! for ray tests, and a binned-SAH [`Bvh`] over the polygons. The shadows crate traces its
//! pictures and baseline shadow rays with them; the indirect crate's ground truth tests
//! visibility between VPLs and receivers with them.

mod bvh;

pub use bvh::Bvh;
use glam::{Vec3, Vec4};

/// A ray segment: the points `origin + t dir` with `t` in `(t_min, t_max)`. `dir` need not be
/// unit length; `t` is measured in multiples of it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Ray {
    /// Where `t = 0` lies.
    pub origin: Vec3,
    /// The direction, `t`'s unit.
    pub dir: Vec3,
    /// The segment starts after this parameter.
    pub t_min: f32,
    /// The segment ends before this parameter.
    pub t_max: f32,
}

impl Ray {
    /// The segment of `origin + t dir` with `t` in `(t_min, t_max)`.
    #[inline]
    pub fn new(origin: Vec3, dir: Vec3, t_min: f32, t_max: f32) -> Self {
        Self {
            origin,
            dir,
            t_min,
            t_max,
        }
    }

    /// The segment from `origin` to `origin + offset` with a unit direction (a shadow ray to a
    /// light), starting after `t_min`.
    #[inline]
    pub fn segment(origin: Vec3, offset: Vec3, t_min: f32) -> Self {
        let dist = offset.length();
        Self::new(origin, offset / dist, t_min, dist)
    }

    /// The point at parameter `t`.
    #[inline]
    pub fn at(&self, t: f32) -> Vec3 {
        self.origin + self.dir * t
    }
}

/// Axis-aligned box.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Aabb {
    /// The lowest corner.
    pub min: Vec3,
    /// The highest corner.
    pub max: Vec3,
}

impl Aabb {
    /// The box of nothing: growing it by a point gives that point.
    pub const EMPTY: Aabb = Aabb {
        min: Vec3::splat(f32::INFINITY),
        max: Vec3::splat(f32::NEG_INFINITY),
    };

    /// The smallest box holding the points.
    pub fn of_points(points: impl IntoIterator<Item = Vec3>) -> Aabb {
        points.into_iter().fold(Aabb::EMPTY, |b, p| b.grow(p))
    }

    /// The box grown to hold `p`.
    pub fn grow(self, p: Vec3) -> Aabb {
        Aabb {
            min: self.min.min(p),
            max: self.max.max(p),
        }
    }

    /// The smallest box holding both.
    pub fn union(self, o: Aabb) -> Aabb {
        Aabb {
            min: self.min.min(o.min),
            max: self.max.max(o.max),
        }
    }

    /// Size along each axis (zero for an empty box).
    pub fn extent(&self) -> Vec3 {
        (self.max - self.min).max(Vec3::ZERO)
    }

    /// The centre.
    pub fn centre(&self) -> Vec3 {
        (self.min + self.max) * 0.5
    }

    /// Surface area (the SAH's measure).
    pub fn surface_area(&self) -> f32 {
        let e = self.extent();
        2.0 * (e.x * e.y + e.y * e.z + e.z * e.x)
    }

    /// Parametric interval `(t0, t1)` of the ray inside the (closed) box, clipped to
    /// `[t_min, t_max]`. A ray parallel to a slab (including one lying on its face) is inside it
    /// when its origin is.
    #[inline]
    pub fn clip_ray(&self, o: Vec3, inv_d: Vec3, t_min: f32, t_max: f32) -> Option<(f32, f32)> {
        let (mut t0, mut t1) = (t_min, t_max);
        for a in 0..3 {
            if inv_d[a].is_infinite() {
                if o[a] < self.min[a] || o[a] > self.max[a] {
                    return None;
                }
                continue;
            }
            let (ta, tb) = (
                (self.min[a] - o[a]) * inv_d[a],
                (self.max[a] - o[a]) * inv_d[a],
            );
            t0 = t0.max(ta.min(tb));
            t1 = t1.min(ta.max(tb));
        }
        (t0 <= t1).then_some((t0, t1))
    }
}

/// A convex planar polygon prepared for ray tests: its plane and inward edge planes.
/// A degenerate polygon (zero area) has a zero normal and is never hit.
#[derive(Clone, Debug)]
pub struct ConvexPolygon {
    /// The corners in order.
    pub vertices: Vec<Vec3>,
    /// Unit normal following the vertex order (Newell), zero when degenerate.
    pub normal: Vec3,
    /// `normal . p` for the points `p` of the plane.
    pub offset: f32,
    edge_planes: Vec<Vec4>,
}

impl ConvexPolygon {
    /// Prepares the polygon through `vertices` (convex, planar, in order).
    pub fn new(vertices: Vec<Vec3>) -> Self {
        let n = vertices.len();
        let mut newell = Vec3::ZERO;
        for i in 0..n {
            let (a, b) = (vertices[i], vertices[(i + 1) % n]);
            newell += Vec3::new(
                (a.y - b.y) * (a.z + b.z),
                (a.z - b.z) * (a.x + b.x),
                (a.x - b.x) * (a.y + b.y),
            );
        }
        let scale = vertices
            .iter()
            .map(|v| (*v - vertices[0]).length_squared())
            .fold(0.0, f32::max);
        // Zero area (collinear or repeated vertices), relative to the polygon's size.
        if n < 3 || !newell.is_finite() || newell.length() <= 1e-7 * scale {
            return Self {
                vertices,
                normal: Vec3::ZERO,
                offset: 0.0,
                edge_planes: Vec::new(),
            };
        }
        let normal = newell.normalize();
        let edge_planes = (0..n)
            .filter_map(|i| edge_plane(normal, vertices[i], vertices[(i + 1) % n]))
            .collect();
        Self {
            offset: normal.dot(vertices[0]),
            vertices,
            normal,
            edge_planes,
        }
    }

    /// Zero area: never hit.
    pub fn is_degenerate(&self) -> bool {
        self.normal == Vec3::ZERO
    }

    /// Area.
    pub fn area(&self) -> f32 {
        let n = self.vertices.len();
        (1..n.saturating_sub(1))
            .map(|i| {
                (self.vertices[i] - self.vertices[0])
                    .cross(self.vertices[i + 1] - self.vertices[0])
                    .length()
                    * 0.5
            })
            .sum()
    }

    /// Perimeter.
    pub fn perimeter(&self) -> f32 {
        let n = self.vertices.len();
        (0..n)
            .map(|i| (self.vertices[(i + 1) % n] - self.vertices[i]).length())
            .sum()
    }

    /// Mean of the corners.
    pub fn centroid(&self) -> Vec3 {
        self.vertices.iter().copied().sum::<Vec3>() / self.vertices.len().max(1) as f32
    }

    /// Bounding box.
    pub fn bounds(&self) -> Aabb {
        Aabb::of_points(self.vertices.iter().copied())
    }

    /// Ray parameter of the hit strictly inside `(t_min, t_max)`, if any.
    #[inline]
    pub fn intersect(&self, o: Vec3, d: Vec3, t_min: f32, t_max: f32) -> Option<f32> {
        let denom = self.normal.dot(d);
        if denom == 0.0 {
            return None;
        }
        let t = (self.offset - self.normal.dot(o)) / denom;
        if !(t > t_min && t < t_max) {
            return None;
        }
        let p = o + d * t;
        self.edge_planes
            .iter()
            .all(|e| e.truncate().dot(p) + e.w >= 0.0)
            .then_some(t)
    }
}

/// The plane through the edge `a -> b` of a polygon with unit normal `normal`, perpendicular to
/// the polygon, as `(m, -m.a)` with `m` pointing into a counter-clockwise polygon; None for a
/// zero-length edge.
#[inline]
fn edge_plane(normal: Vec3, a: Vec3, b: Vec3) -> Option<Vec4> {
    let m = normal.cross(b - a).try_normalize()?;
    Some(m.extend(-m.dot(a)))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn square_is_hit_inside_and_missed_outside() {
        let sq = ConvexPolygon::new(vec![
            Vec3::new(0.0, 0.0, 0.0),
            Vec3::new(1.0, 0.0, 0.0),
            Vec3::new(1.0, 1.0, 0.0),
            Vec3::new(0.0, 1.0, 0.0),
        ]);
        let d = Vec3::new(0.0, 0.0, -1.0);
        assert_eq!(
            sq.intersect(Vec3::new(0.5, 0.5, 2.0), d, 0.0, 10.0),
            Some(2.0)
        );
        assert_eq!(sq.intersect(Vec3::new(1.5, 0.5, 2.0), d, 0.0, 10.0), None);
        assert_eq!(sq.intersect(Vec3::new(0.5, 0.5, 2.0), d, 0.0, 1.0), None);
        assert!((sq.area() - 1.0).abs() < 1e-6 && (sq.perimeter() - 4.0).abs() < 1e-6);
    }

    #[test]
    fn collinear_polygon_is_degenerate_and_never_hit() {
        let p = ConvexPolygon::new(vec![Vec3::ZERO, Vec3::X, Vec3::X * 2.0]);
        assert!(p.is_degenerate());
        assert_eq!(
            p.intersect(Vec3::new(1.0, 0.0, 1.0), -Vec3::Z, 0.0, 10.0),
            None
        );
    }
}
