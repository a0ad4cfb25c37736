//! Frames and attitude. World and body frames are x forward, y left, z up (MuJoCo's convention for
//! this model); quaternions are MuJoCo's (w, x, y, z) order.

pub use glam::{DQuat as Quat, DVec3 as Vec3};

/// Builds a quaternion from MuJoCo's (w, x, y, z) order.
pub fn quat_from_wxyz(q: [f64; 4]) -> Quat {
    Quat::from_xyzw(q[1], q[2], q[3], q[0])
}

/// MuJoCo's (w, x, y, z) order of a quaternion.
pub fn quat_to_wxyz(q: Quat) -> [f64; 4] {
    [q.w, q.x, q.y, q.z]
}

/// Expresses a world-frame vector in the body frame of orientation `q`.
pub fn quat_rotate_inverse(q: Quat, v: Vec3) -> Vec3 {
    q.inverse() * v
}

/// Roll, pitch and yaw in radians (Z-Y-X order) with the signs a pilot expects:
/// roll positive = right wing down, pitch positive = nose up, yaw positive = nose turns left
/// (counter-clockwise seen from above).
pub fn quat_to_euler(q: Quat) -> [f64; 3] {
    let (yaw, pitch_about_y, roll) = q.to_euler(glam::EulerRot::ZYX);
    // A positive rotation about +y (pointing left) moves the nose down.
    [roll, -pitch_about_y, yaw]
}

/// The orientation with the given roll, pitch and yaw (signs as in [`quat_to_euler`]).
pub fn quat_from_euler(roll_rad: f64, pitch_rad: f64, yaw_rad: f64) -> Quat {
    Quat::from_euler(glam::EulerRot::ZYX, yaw_rad, -pitch_rad, roll_rad)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn euler_round_trip_and_signs() {
        let q = quat_from_euler(0.1, 0.3, -0.7);
        let [roll, pitch, yaw] = quat_to_euler(q);
        assert!((roll - 0.1).abs() < 1e-12 && (pitch - 0.3).abs() < 1e-12 && (yaw + 0.7).abs() < 1e-12);
        // Nose up: the body's x axis points above the horizon.
        let nose = quat_from_euler(0.0, 0.4, 0.0) * Vec3::X;
        assert!(nose.z > 0.3);
        // Right wing down: the body's -y axis (right wing) points below the horizon.
        let right_wing = quat_from_euler(0.4, 0.0, 0.0) * Vec3::NEG_Y;
        assert!(right_wing.z < -0.3);
        // Positive yaw turns the nose left (+y).
        let nose = quat_from_euler(0.0, 0.0, 0.4) * Vec3::X;
        assert!(nose.y > 0.3);
    }

    #[test]
    fn body_frame_of_a_level_robot_is_the_world_frame() {
        let v = Vec3::new(1.0, 2.0, 3.0);
        assert!((quat_rotate_inverse(Quat::IDENTITY, v) - v).length() < 1e-12);
        let yawed = quat_from_euler(0.0, 0.0, std::f64::consts::FRAC_PI_2);
        // Flying along world +y, a point ahead in the world is straight ahead in the body.
        let ahead = quat_rotate_inverse(yawed, Vec3::Y);
        assert!((ahead - Vec3::X).length() < 1e-12);
        let [w, x, y, z] = quat_to_wxyz(yawed);
        assert_eq!(quat_from_wxyz([w, x, y, z]), yawed);
    }
}
