//! Welding points by position: one id for all points within a tolerance.

use std::collections::HashMap;

use glam::Vec3;

/// Gives each point the id of the first earlier point within `tol` of it (Euclidean),
/// scanning in input order. Returns the id of every input point and the unique points.
pub fn weld_points(points: &[Vec3], tol: f32) -> (Vec<u32>, Vec<Vec3>) {
    let cell = if tol > 0.0 { tol * 2.0 } else { 1.0 };
    let key = |p: Vec3| (p / cell).floor().as_ivec3();
    let mut grid: HashMap<glam::IVec3, Vec<u32>> = HashMap::new();
    let mut unique: Vec<Vec3> = Vec::new();
    let mut ids = Vec::with_capacity(points.len());
    for &p in points {
        let k = key(p);
        let mut found = None;
        'search: for dz in -1..=1 {
            for dy in -1..=1 {
                for dx in -1..=1 {
                    if let Some(list) = grid.get(&(k + glam::IVec3::new(dx, dy, dz))) {
                        for &id in list {
                            if unique[id as usize] == p || (unique[id as usize] - p).length() <= tol
                            {
                                found = Some(id);
                                break 'search;
                            }
                        }
                    }
                }
            }
        }
        let id = found.unwrap_or_else(|| {
            unique.push(p);
            let id = (unique.len() - 1) as u32;
            grid.entry(k).or_default().push(id);
            id
        });
        ids.push(id);
    }
    (ids, unique)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn welds_within_tolerance_only() {
        let pts = [
            Vec3::ZERO,
            Vec3::new(1e-7, 0.0, 0.0),
            Vec3::X,
            Vec3::new(0.0, 1e-3, 0.0),
        ];
        let (ids, unique) = weld_points(&pts, 1e-6);
        assert_eq!(ids, vec![0, 0, 1, 2]);
        assert_eq!(unique.len(), 3);
    }
}
