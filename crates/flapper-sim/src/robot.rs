//! What the rest of the code may assume about the robot: the names in `models/flapper.xml` and the
//! paper's joint order q1..q5. The numbers themselves live in the MJCF file, written once.

use std::path::PathBuf;

/// The robot's MJCF, compiled into the binary so that `flapper` runs from any directory.
pub const ROBOT_MJCF: &str = include_str!("../../../models/flapper.xml");

/// Where the robot's MJCF lives in the repository (for tools that want the file itself).
pub fn default_model_path() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../models/flapper.xml")
}

/// Number of actuated joints (n_j in the paper).
pub const N_ACTUATED_JOINTS: usize = 5;

/// The paper's cruise speed (m/s): its longitudinal references, launches and analyses fly at it.
pub const CRUISE_SPEED_MPS: f64 = 3.8;

/// The five actuated joints in the paper's order q1..q5. Each has a hinge joint and a position
/// actuator of the same name in the MJCF.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum ActuatedJoint {
    /// q1: left wing flap; positive = wing tip up.
    FlapLeft,
    /// q2: left wing pitch (feathering); negative = leading edge up.
    PitchLeft,
    /// q3: right wing flap; positive = wing tip up.
    FlapRight,
    /// q4: right wing pitch (feathering); negative = leading edge up.
    PitchRight,
    /// q5: tail pitch; negative = trailing edge up (pitches the robot nose up).
    TailPitch,
}

impl ActuatedJoint {
    pub const ALL: [ActuatedJoint; N_ACTUATED_JOINTS] =
        [Self::FlapLeft, Self::PitchLeft, Self::FlapRight, Self::PitchRight, Self::TailPitch];

    /// The joint's (and its actuator's) name in the MJCF.
    pub const fn name(self) -> &'static str {
        match self {
            Self::FlapLeft => "flap_left",
            Self::PitchLeft => "pitch_left",
            Self::FlapRight => "flap_right",
            Self::PitchRight => "pitch_right",
            Self::TailPitch => "tail_pitch",
        }
    }

    /// Position in q1..q5 (0-based).
    pub const fn index(self) -> usize {
        self as usize
    }
}

/// The four rigid bodies, free base first.
pub const BODY_NAMES: [&str; 4] = ["main_body", "wing_left", "wing_right", "tail"];

/// Geoms that use MuJoCo's ellipsoid fluid model (the main body uses the inertia-box model).
pub const LIFTING_SURFACE_GEOMS: [&str; 3] = ["wing_left", "wing_right", "tail"];

/// The free joint of the main body.
pub const BASE_JOINT: &str = "base";
