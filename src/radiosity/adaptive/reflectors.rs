//! The reflecting elements of a solved level as secondary light sources: points drawn on them by the
//! power they reflect, and the part of their light that shadow rays find blocked at a point. A
//! ceiling lit by an uplighter lights the floor as a lamp would, and a table's shadow of it is as
//! sharp as the table is near the floor; `shadow_boundaries` tests both kinds of source.

use glam::Vec3;

use crate::accel::Accel;
use crate::mesh::Mesh;
use crate::rng::Pcg32;
use crate::transport::emitters::uniform_triangle_point;

/// Reflected exitance per element, R = max(B − E, 0), and a table to draw elements by reflected power
/// Φⱼ = Aⱼ·R̄ⱼ (R̄ the mean over the channels).
#[derive(Clone, Debug)]
pub struct Reflectors {
    reflected_exitance: Vec<Vec3>,
    /// Cumulative Φⱼ/Φ, increasing, the last 1.
    cumulative: Vec<f64>,
    /// Φⱼ/Φ.
    probability: Vec<f64>,
}

/// A point drawn on a reflecting element.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ReflectorSample {
    pub point: Vec3,
    pub element: usize,
    /// 1/p_A(y) = Aⱼ/(Φⱼ/Φ): the inverse of the area density the point was drawn with.
    pub inverse_density: f32,
}

impl Reflectors {
    /// The elements of `mesh` that reflect light in the solution `element_exitance`; `None` where none
    /// does.
    pub fn new(mesh: &Mesh, element_exitance: &[Vec3]) -> Option<Reflectors> {
        let e = &mesh.elements;
        let reflected_exitance: Vec<Vec3> =
            (0..e.len()).map(|i| (element_exitance[i] - e.emission[i]).max(Vec3::ZERO)).collect();
        let power: Vec<f64> =
            (0..e.len()).map(|i| f64::from(e.area[i]) * f64::from(reflected_exitance[i].element_sum()) / 3.0).collect();
        let total: f64 = power.iter().sum();
        if !(total > 0.0 && total.is_finite()) {
            return None;
        }
        let probability: Vec<f64> = power.iter().map(|p| p / total).collect();
        let cumulative = probability
            .iter()
            .scan(0.0, |sum, p| {
                *sum += p;
                Some(*sum)
            })
            .collect();
        Some(Reflectors { reflected_exitance, cumulative, probability })
    }

    /// A point drawn on element j with probability Φⱼ/Φ (`xi` ∈ [0, 1) picks the element), uniformly
    /// by area within it (`s`, `r`, `pick` ∈ [0, 1): a quad's two triangles are picked by area).
    pub fn sample(&self, mesh: &Mesh, xi: f64, s: f32, r: f32, pick: f32) -> Option<ReflectorSample> {
        let last = self.cumulative.len().checked_sub(1)?;
        let element = self.cumulative.partition_point(|&c| c <= xi).min(last);
        if self.probability[element] <= 0.0 {
            return None;
        }
        let p: Vec<Vec3> = mesh.elements.polygon(&mesh.positions, element).collect();
        let triangle = match p[..] {
            [a, b, c, d] => {
                let first = (b - a).cross(c - a).length();
                let second = (c - a).cross(d - a).length();
                if pick * (first + second) < first {
                    [a, b, c]
                } else {
                    [a, c, d]
                }
            }
            [a, b, c] => [a, b, c],
            _ => return None,
        };
        let inverse_density = (f64::from(mesh.elements.area[element]) / self.probability[element]) as f32;
        Some(ReflectorSample { point: uniform_triangle_point(triangle, s, r), element, inverse_density })
    }

    /// `samples` points drawn stratified over Φ (the same points serve every corner of an element, so
    /// that the corners differ by what lies between, not by the draw).
    pub fn draw(&self, mesh: &Mesh, samples: u32, rng: &mut Pcg32) -> Vec<ReflectorSample> {
        (0..samples)
            .filter_map(|k| {
                let xi = (f64::from(k) + rng.next_f64()) / f64::from(samples);
                let (s, r, pick) = (rng.next_f32(), rng.next_f32(), rng.next_f32());
                self.sample(mesh, xi, s, r, pick)
            })
            .collect()
    }

    /// The irradiance the reflectors' points would add at x (unit normal n, x already off its surface)
    /// with nothing in the way, the part shadow rays find blocked:
    ///
    /// Eᵇ(x) ≈ (1/K) Σ_k R_j(k) cos θ_x cos θ_k / (π d_k²) · (1/p_A(y_k)) · (1 − V(x, y_k)),
    ///
    /// K = `points.len()` (a point drawn on the element x lies on counts as not blocked).
    pub fn blocked_irradiance(&self, mesh: &Mesh, accel: &Accel, x: Vec3, n: Vec3, points: &[ReflectorSample]) -> Vec3 {
        let mut blocked = Vec3::ZERO;
        for sample in points {
            let to_point = sample.point - x;
            let dist2 = to_point.length_squared();
            if !(dist2 > 0.0) {
                continue;
            }
            let dist = dist2.sqrt();
            let w = to_point / dist;
            let (cos_here, cos_there) = (n.dot(w), -mesh.elements.normal[sample.element].dot(w));
            if cos_here <= 0.0 || cos_there <= 0.0 {
                continue;
            }
            // Stop short of the point's own surface, which the ray would otherwise graze.
            if accel.occluded(x, w, dist * (1.0 - 1e-3)) {
                let g = cos_here * cos_there / (std::f32::consts::PI * dist2);
                blocked += self.reflected_exitance[sample.element] * (g * sample.inverse_density);
            }
        }
        blocked / points.len().max(1) as f32
    }
}
