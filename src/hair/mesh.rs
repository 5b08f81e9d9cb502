//! Triangle meshes used as occluders (heads), from OBJ or glTF.

use super::error::HairError;
use glam::Vec3;
use std::path::Path;

#[derive(Clone, Debug, Default, PartialEq)]
pub struct TriangleMesh {
    pub positions: Vec<Vec3>,
    pub triangles: Vec<[u32; 3]>,
}

impl TriangleMesh {
    /// Appends another mesh.
    pub fn append(&mut self, other: &TriangleMesh) {
        let base = self.positions.len() as u32;
        self.positions.extend_from_slice(&other.positions);
        self.triangles.extend(
            other
                .triangles
                .iter()
                .map(|t| [t[0] + base, t[1] + base, t[2] + base]),
        );
    }

    /// Distance from `p` to the closest point of the mesh (brute force over triangles).
    pub fn distance(&self, p: Vec3) -> f32 {
        self.triangles
            .iter()
            .map(|t| {
                let [a, b, c] = t.map(|i| self.positions[i as usize]);
                closest_point_on_triangle(p, a, b, c).distance(p)
            })
            .fold(f32::INFINITY, f32::min)
    }

    /// Area-weighted vertex normals (the triangles' winding gives the outside: counter-clockwise seen
    /// from outside, as OBJ and glTF have it).
    pub fn vertex_normals(&self) -> Vec<Vec3> {
        let mut n = vec![Vec3::ZERO; self.positions.len()];
        for t in &self.triangles {
            let [a, b, c] = t.map(|i| self.positions[i as usize]);
            let face = (b - a).cross(c - a);
            for &i in t {
                n[i as usize] += face;
            }
        }
        n.into_iter().map(|v| v.normalize_or(Vec3::Y)).collect()
    }

    /// The nearest hit of the ray (origin, unit direction) beyond `t_min`: (distance, triangle,
    /// barycentrics (u, v) of the second and third vertices), Moller-Trumbore, both sides.
    pub fn intersect(&self, origin: Vec3, dir: Vec3, t_min: f32) -> Option<(f32, usize, [f32; 2])> {
        let mut best: Option<(f32, usize, [f32; 2])> = None;
        for (k, t) in self.triangles.iter().enumerate() {
            let [a, b, c] = t.map(|i| self.positions[i as usize]);
            if let Some((d, uv)) = ray_triangle(origin, dir, a, b, c)
                && d > t_min
                && best.is_none_or(|(bd, _, _)| d < bd)
            {
                best = Some((d, k, uv));
            }
        }
        best
    }

    pub fn bounds(&self) -> (Vec3, Vec3) {
        self.positions.iter().fold(
            (Vec3::splat(f32::MAX), Vec3::splat(f32::MIN)),
            |(lo, hi), p| (lo.min(*p), hi.max(*p)),
        )
    }
}

/// Distance along the ray (origin, dir) to triangle abc and the barycentrics (u, v) of b and c at the
/// hit (Moller and Trumbore 1997), either side; None when it misses or runs parallel.
pub fn ray_triangle(origin: Vec3, dir: Vec3, a: Vec3, b: Vec3, c: Vec3) -> Option<(f32, [f32; 2])> {
    let (e1, e2) = (b - a, c - a);
    let p = dir.cross(e2);
    let det = e1.dot(p);
    if det.abs() < 1e-12 * e1.length_squared().max(e2.length_squared()) {
        return None;
    }
    let inv = 1.0 / det;
    let s = origin - a;
    let u = s.dot(p) * inv;
    if !(0.0..=1.0).contains(&u) {
        return None;
    }
    let q = s.cross(e1);
    let v = dir.dot(q) * inv;
    if v < 0.0 || u + v > 1.0 {
        return None;
    }
    Some((e2.dot(q) * inv, [u, v]))
}

/// Closest point on triangle abc to p (Ericson, Real-Time Collision Detection, 5.1.5).
pub fn closest_point_on_triangle(p: Vec3, a: Vec3, b: Vec3, c: Vec3) -> Vec3 {
    let (ab, ac, ap) = (b - a, c - a, p - a);
    let (d1, d2) = (ab.dot(ap), ac.dot(ap));
    if d1 <= 0.0 && d2 <= 0.0 {
        return a;
    }
    let bp = p - b;
    let (d3, d4) = (ab.dot(bp), ac.dot(bp));
    if d3 >= 0.0 && d4 <= d3 {
        return b;
    }
    let vc = d1 * d4 - d3 * d2;
    if vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0 {
        return a + ab * (d1 / (d1 - d3));
    }
    let cp = p - c;
    let (d5, d6) = (ab.dot(cp), ac.dot(cp));
    if d6 >= 0.0 && d5 <= d6 {
        return c;
    }
    let vb = d5 * d2 - d1 * d6;
    if vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0 {
        return a + ac * (d2 / (d2 - d6));
    }
    let va = d3 * d6 - d5 * d4;
    if va <= 0.0 && (d4 - d3) >= 0.0 && (d5 - d6) >= 0.0 {
        return b + (c - b) * ((d4 - d3) / ((d4 - d3) + (d5 - d6)));
    }
    let denom = 1.0 / (va + vb + vc);
    a + ab * (vb * denom) + ac * (vc * denom)
}

/// Reads an OBJ mesh (all objects merged, polygons triangulated) from bytes.
pub fn read_obj(bytes: &[u8], path: &Path) -> Result<TriangleMesh, HairError> {
    let mut reader = std::io::BufReader::new(bytes);
    let opts = tobj::LoadOptions {
        triangulate: true,
        single_index: true,
        ..Default::default()
    };
    // Materials are irrelevant for an occluder: ignore the .mtl reference.
    let (models, _) =
        tobj::load_obj_buf(&mut reader, &opts, |_| Err(tobj::LoadError::OpenFileFailed))
            .map_err(|e| HairError::format(path, format!("invalid OBJ: {e}")))?;
    let mut mesh = TriangleMesh::default();
    for m in &models {
        let p = &m.mesh.positions;
        if p.len() % 3 != 0 || m.mesh.indices.len() % 3 != 0 {
            return Err(HairError::format(
                path,
                format!("object '{}' has malformed arrays", m.name),
            ));
        }
        let part = TriangleMesh {
            positions: p
                .chunks_exact(3)
                .map(|c| Vec3::new(c[0], c[1], c[2]))
                .collect(),
            triangles: m
                .mesh
                .indices
                .chunks_exact(3)
                .map(|c| [c[0], c[1], c[2]])
                .collect(),
        };
        validate_mesh(&part, path)?;
        mesh.append(&part);
    }
    if mesh.triangles.is_empty() {
        return Err(HairError::format(path, "the OBJ file has no triangles"));
    }
    Ok(mesh)
}

pub fn validate_mesh(mesh: &TriangleMesh, path: &Path) -> Result<(), HairError> {
    if let Some(k) = mesh.positions.iter().position(|p| !p.is_finite()) {
        return Err(HairError::format(path, format!("vertex {k} is not finite")));
    }
    let n = mesh.positions.len() as u32;
    if let Some(t) = mesh.triangles.iter().find(|t| t.iter().any(|&i| i >= n)) {
        return Err(HairError::format(
            path,
            format!("triangle {t:?} indexes past the {n} vertices"),
        ));
    }
    Ok(())
}
