//! Plane polygons given as vertex lists `[[x, y], ...]` (m): a soil region's outline and a
//! rigid body's section share these rules, so that both refuse the same shapes.

/// Bounds (m) of a polygon's vertices `[x, y]`, z 0..0.
pub fn bounds(vertices: &[Vec<f64>]) -> ([f64; 3], [f64; 3]) {
    let mut lo = [f64::INFINITY, f64::INFINITY, 0.0];
    let mut hi = [f64::NEG_INFINITY, f64::NEG_INFINITY, 0.0];
    for v in vertices {
        for a in 0..2 {
            lo[a] = lo[a].min(v[a]);
            hi[a] = hi[a].max(v[a]);
        }
    }
    (lo, hi)
}

/// Twice the signed area of a polygon (positive counter-clockwise).
pub fn signed_area(v: &[Vec<f64>]) -> f64 {
    (0..v.len())
        .map(|i| {
            let (a, b) = (&v[i], &v[(i + 1) % v.len()]);
            a[0] * b[1] - b[0] * a[1]
        })
        .sum()
}

/// Even-odd rule point-in-polygon test.
pub fn contains(vertices: &[Vec<f64>], x: f64, y: f64) -> bool {
    let mut inside = false;
    let mut j = vertices.len() - 1;
    for i in 0..vertices.len() {
        let (a, b) = (&vertices[i], &vertices[j]);
        if (a[1] > y) != (b[1] > y) && x < (b[0] - a[0]) * (y - a[1]) / (b[1] - a[1]) + a[0] {
            inside = !inside;
        }
        j = i;
    }
    inside
}

/// Why a polygon cannot be filled, if it cannot: zero area, or two edges that cross or
/// touch other than at their shared vertex (the even-odd fill of a self-intersecting
/// polygon is rarely the region meant).
pub fn fault(vertices: &[Vec<f64>]) -> Option<String> {
    let m = vertices.len();
    let p = |i: usize| (vertices[i % m][0], vertices[i % m][1]);
    let twice_area = signed_area(vertices);
    if !(twice_area.abs() > 0.0 && twice_area.is_finite()) {
        return Some("the polygon encloses no area".into());
    }
    let cross =
        |o: (f64, f64), a: (f64, f64), b: (f64, f64)| (a.0 - o.0) * (b.1 - o.1) - (a.1 - o.1) * (b.0 - o.0);
    let on = |a: (f64, f64), b: (f64, f64), q: (f64, f64)| {
        q.0 >= a.0.min(b.0) && q.0 <= a.0.max(b.0) && q.1 >= a.1.min(b.1) && q.1 <= a.1.max(b.1)
    };
    // Segments a-b and c-d meet (proper crossing, or one end on the other segment).
    let meet = |a, b, c, d| {
        let (d1, d2, d3, d4) = (cross(c, d, a), cross(c, d, b), cross(a, b, c), cross(a, b, d));
        (d1 * d2 < 0.0 && d3 * d4 < 0.0)
            || (d1 == 0.0 && on(c, d, a))
            || (d2 == 0.0 && on(c, d, b))
            || (d3 == 0.0 && on(a, b, c))
            || (d4 == 0.0 && on(a, b, d))
    };
    for i in 0..m {
        for j in i + 1..m {
            // Neighbouring edges share a vertex; they fault only by folding back on each other.
            let adjacent = j == i + 1 || (i == 0 && j == m - 1);
            let (a, b, c, d) = (p(i), p(i + 1), p(j), p(j + 1));
            if adjacent {
                let (shared, u, v) = if j == i + 1 { (b, a, d) } else { (a, b, c) };
                let collinear_back = cross(shared, u, v) == 0.0
                    && (u.0 - shared.0) * (v.0 - shared.0) + (u.1 - shared.1) * (v.1 - shared.1) > 0.0;
                if collinear_back {
                    return Some(format!("edges {i} and {j} fold back on each other"));
                }
            } else if meet(a, b, c, d) {
                return Some(format!(
                    "edges {i} ({:?} to {:?}) and {j} ({:?} to {:?}) cross: give the vertices of a simple polygon, in order",
                    vertices[i], vertices[(i + 1) % m], vertices[j], vertices[(j + 1) % m]
                ));
            }
        }
    }
    None
}
