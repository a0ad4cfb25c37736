//! Where the camera looks from: MuJoCo's free camera (look-at point, distance, azimuth, elevation),
//! a chase camera that follows a flight, and a fixed camera that frames a whole manoeuvre.

/// MuJoCo's free camera. Azimuth 0 looks along +x, 90 along +y; negative elevation looks down.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CameraView {
    pub lookat_m: [f64; 3],
    pub distance_m: f64,
    pub azimuth_deg: f64,
    pub elevation_deg: f64,
}

impl CameraView {
    /// Unit vectors (forward, right, up) of the view.
    fn axes(&self) -> ([f64; 3], [f64; 3], [f64; 3]) {
        let (a, e) = (self.azimuth_deg.to_radians(), self.elevation_deg.to_radians());
        let forward = [e.cos() * a.cos(), e.cos() * a.sin(), e.sin()];
        let right = [a.sin(), -a.cos(), 0.0];
        let up = [
            right[1] * forward[2] - right[2] * forward[1],
            right[2] * forward[0] - right[0] * forward[2],
            right[0] * forward[1] - right[1] * forward[0],
        ];
        (forward, right, up)
    }
}

fn dot(a: [f64; 3], b: [f64; 3]) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

/// A fixed camera at the given azimuth and elevation that sees every point, with a margin, in a
/// picture of `aspect` = width / height and vertical field of view `fovy_deg`.
pub fn framing_camera(
    points_m: &[[f64; 3]],
    azimuth_deg: f64,
    elevation_deg: f64,
    aspect: f64,
    fovy_deg: f64,
) -> Option<CameraView> {
    if points_m.is_empty() {
        return None;
    }
    let mut lo = [f64::MAX; 3];
    let mut hi = [f64::MIN; 3];
    for p in points_m {
        for i in 0..3 {
            lo[i] = lo[i].min(p[i]);
            hi[i] = hi[i].max(p[i]);
        }
    }
    let lookat_m = [(lo[0] + hi[0]) / 2.0, (lo[1] + hi[1]) / 2.0, (lo[2] + hi[2]) / 2.0];
    let mut view = CameraView { lookat_m, distance_m: 1.0, azimuth_deg, elevation_deg };
    let (forward, right, up) = view.axes();
    let tan_half = (fovy_deg.to_radians() / 2.0).tan();
    let mut distance: f64 = 1.0;
    for p in points_m {
        let d = [p[0] - lookat_m[0], p[1] - lookat_m[1], p[2] - lookat_m[2]];
        // The point must be inside the frustum: |up offset| <= (D - forward offset) tan, same sideways.
        let along = dot(d, forward);
        let need = along + (dot(d, up).abs() / tan_half).max(dot(d, right).abs() / (aspect * tan_half));
        distance = distance.max(need);
    }
    // Margin for the robot's own size (0.5 m half-span) and a border.
    view.distance_m = 1.15 * distance + 1.0;
    Some(view)
}

/// A chase camera for every pose: behind the robot along its smoothed direction of travel, looking
/// at it slightly from above. `positions_m` at `fps` frames per second.
pub fn chase_cameras(positions_m: &[[f64; 3]], fps: f64, distance_m: f64, elevation_deg: f64) -> Vec<CameraView> {
    let n = positions_m.len();
    let window = (fps.max(1.0)).round() as usize; // heading over about one second each side
    let mut headings = Vec::with_capacity(n);
    let mut previous: Option<f64> = None;
    for k in 0..n {
        let (a, b) = (positions_m[k.saturating_sub(window)], positions_m[(k + window).min(n - 1)]);
        let (dx, dy) = (b[0] - a[0], b[1] - a[1]);
        let raw = if dx.hypot(dy) > 0.2 { dy.atan2(dx) } else { previous.unwrap_or(0.0) };
        // Unwrap, so smoothing never swings the long way round.
        let heading = match previous {
            Some(p) => {
                p + (raw - p + std::f64::consts::PI).rem_euclid(2.0 * std::f64::consts::PI) - std::f64::consts::PI
            }
            None => raw,
        };
        headings.push(heading);
        previous = Some(heading);
    }
    // Exponential smoothing forwards (about half a second).
    let alpha = 1.0 / (0.5 * fps).max(1.0);
    let mut smooth = headings.first().copied().unwrap_or(0.0);
    positions_m
        .iter()
        .zip(headings)
        .map(|(p, h)| {
            smooth += alpha * (h - smooth);
            CameraView { lookat_m: *p, distance_m, azimuth_deg: smooth.to_degrees(), elevation_deg }
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_framing_camera_sees_every_point() {
        let points: Vec<[f64; 3]> =
            (0..50).map(|k| [k as f64 * 0.4, (k as f64 * 0.3).sin() * 3.0, 10.0 + (k as f64 * 0.2).cos()]).collect();
        for (azimuth, elevation) in [(90.0, 0.0), (0.0, -89.0), (45.0, -30.0)] {
            let view = framing_camera(&points, azimuth, elevation, 16.0 / 9.0, 45.0).unwrap();
            let (forward, right, up) = view.axes();
            let eye: Vec<f64> = (0..3).map(|i| view.lookat_m[i] - view.distance_m * forward[i]).collect();
            let tan_half = 22.5f64.to_radians().tan();
            for p in &points {
                let d = [p[0] - eye[0], p[1] - eye[1], p[2] - eye[2]];
                let depth = dot(d, forward);
                assert!(depth > 0.0);
                assert!(dot(d, up).abs() <= depth * tan_half, "point {p:?} above or below the view");
                assert!(dot(d, right).abs() <= depth * tan_half * 16.0 / 9.0, "point {p:?} beside the view");
            }
        }
    }

    #[test]
    fn the_chase_camera_looks_along_the_travel() {
        // Flying along +y at 4 m/s, 25 frames per second: azimuth 90 (looking along +y).
        let points: Vec<[f64; 3]> = (0..100).map(|k| [0.0, 4.0 * k as f64 / 25.0, 10.0]).collect();
        let cameras = chase_cameras(&points, 25.0, 2.5, -15.0);
        assert_eq!(cameras.len(), 100);
        assert!((cameras[50].azimuth_deg - 90.0).abs() < 1e-9);
        assert_eq!(cameras[50].lookat_m, points[50]);
    }
}
