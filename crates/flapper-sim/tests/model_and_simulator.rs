//! The model as built matches the paper, the simulator layer reads and edits what it says, and bad
//! input or a broken simulation becomes an error value.

#![allow(clippy::approx_constant)] // 3.14 here is the paper's Kutta-lift coefficient, not pi

use flapper_sim::{
    ActuatedJoint, FluidCoefficients, InitialState, ModelError, RobotModel, SimFault, Vec3, default_model_path,
    quat_from_euler,
};

fn within(value: f64, expected: f64, relative: f64) -> bool {
    (value - expected).abs() <= relative * expected.abs()
}

#[test]
fn model_as_built_matches_the_paper_within_one_percent() {
    let robot = RobotModel::flapper().unwrap();
    let d = robot.dimensions();
    assert!(within(d.total_mass_kg, 0.31, 0.01), "mass {}", d.total_mass_kg);
    assert!(within(d.wingspan_m, 0.995, 0.01), "wingspan {}", d.wingspan_m);
    assert!(within(d.mean_chord_m, 0.17, 0.01), "mean chord {}", d.mean_chord_m);
    assert_eq!(d.degrees_of_freedom, 11);
    assert_eq!(d.actuators, 5);
    assert!((robot.timestep_s() - 0.004).abs() < 1e-12);
}

#[test]
fn the_file_on_disk_is_the_compiled_in_model() {
    let from_file = RobotModel::load(&default_model_path()).unwrap();
    assert_eq!(from_file.dimensions().total_mass_kg, RobotModel::flapper().unwrap().dimensions().total_mass_kg);
}

#[test]
fn missing_model_file_names_the_file() {
    let err = RobotModel::load(std::path::Path::new("/nonexistent/robot.xml")).unwrap_err();
    assert!(matches!(err, ModelError::Read { .. }));
    assert!(err.to_string().contains("/nonexistent/robot.xml"), "{err}");
}

#[test]
fn malformed_model_carries_mujocos_message() {
    let dir = std::env::temp_dir().join(format!("flapper-bad-model-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join("broken.xml");
    std::fs::write(&path, "<mujoco><worldbody><body><geom size=\"0.1\"></body></mujoco>").unwrap();
    let err = RobotModel::load(&path).unwrap_err();
    let text = err.to_string();
    assert!(matches!(err, ModelError::Load { .. }), "{text}");
    assert!(text.contains("broken.xml"), "{text}");
    assert!(text.len() > "MuJoCo rejected model ''".len() + path.display().to_string().len() + 5, "{text}");
}

#[test]
fn a_model_without_the_robots_joints_is_rejected() {
    let err = RobotModel::from_mjcf(
        "<mujoco><worldbody><body name='main_body'><freejoint name='base'/><geom size='0.1'/></body></worldbody></mujoco>",
        "other.xml",
    )
    .unwrap_err();
    assert!(matches!(err, ModelError::NotTheRobot { .. }));
    assert!(err.to_string().contains("wing_left") || err.to_string().contains("flap_left"), "{err}");
}

#[test]
fn unknown_names_in_parameter_edits_are_errors() {
    let mut sim = RobotModel::flapper().unwrap().instantiate().unwrap();
    let err = sim.set_body_mass("propeller", 0.1).unwrap_err();
    assert!(err.to_string().contains("propeller") && err.to_string().contains("main_body"), "{err}");
    assert!(sim.set_joint_damping("flap_middle", 0.1).unwrap_err().to_string().contains("flap_middle"));
    assert!(sim.added_mass("main_body").is_err(), "the main body uses the inertia-box model");
    assert!(sim.set_body_mass("main_body", -1.0).is_err());
    assert!(sim.set_wind(Vec3::new(f64::NAN, 0.0, 0.0)).is_err());
}

#[test]
fn parameter_edits_read_back_and_restore() {
    let mut sim = RobotModel::flapper().unwrap().instantiate().unwrap();
    let mass = sim.body_mass("wing_left").unwrap();
    sim.set_body_mass("wing_left", mass * 1.1).unwrap();
    assert!(within(sim.body_mass("wing_left").unwrap(), mass * 1.1, 1e-12));
    let inertia = sim.body_inertia("tail").unwrap();
    sim.set_body_inertia("tail", inertia.map(|i| i * 0.9)).unwrap();
    assert!(within(sim.body_inertia("tail").unwrap()[0], inertia[0] * 0.9, 1e-12));
    let com = sim.body_com("main_body").unwrap();
    sim.set_body_com("main_body", com + Vec3::new(0.01, 0.0, 0.0)).unwrap();
    assert!((sim.body_com("main_body").unwrap().x - com.x - 0.01).abs() < 1e-12);
    sim.set_joint_damping("tail_pitch", 0.005).unwrap();
    assert_eq!(sim.joint_damping("tail_pitch").unwrap(), 0.005);
    let paper = sim.fluid_coefficients("wing_right").unwrap();
    assert_eq!(paper.to_array(), [0.2, 0.12, 1.5, 3.14, 1.0]);
    sim.set_fluid_coefficients("wing_right", FluidCoefficients { kutta_lift: 2.0, ..paper }).unwrap();
    assert_eq!(sim.fluid_coefficients("wing_right").unwrap().kutta_lift, 2.0);
    let added = sim.added_mass("tail").unwrap();
    assert!(added.iter().all(|m| *m > 0.0), "MuJoCo computes added mass for ellipsoids: {added:?}");
    sim.set_added_mass("tail", added.map(|m| m * 1.1)).unwrap();
    sim.set_added_inertia("tail", sim.added_inertia("tail").unwrap().map(|m| m * 0.9)).unwrap();
    sim.set_wind(Vec3::new(1.0, -2.0, 0.5)).unwrap();
    assert_eq!(sim.wind(), Vec3::new(1.0, -2.0, 0.5));

    // Other instances keep their own parameters.
    let other = RobotModel::flapper().unwrap().instantiate().unwrap();
    assert_eq!(other.wind(), Vec3::ZERO);
    assert!(within(other.body_mass("wing_left").unwrap(), mass, 1e-12));

    sim.restore_nominal_parameters();
    assert_eq!(sim.wind(), Vec3::ZERO);
    assert!(within(sim.body_mass("wing_left").unwrap(), mass, 1e-12));
    assert_eq!(sim.fluid_coefficients("wing_right").unwrap(), paper);
}

#[test]
fn fluid_coefficient_edits_change_the_flight_at_once() {
    let robot = RobotModel::flapper().unwrap();
    let glide = InitialState {
        linear_velocity_mps: Vec3::new(3.8, 0.0, 0.0),
        orientation: quat_from_euler(0.0, 0.13, 0.0),
        ..InitialState::default()
    };
    let altitude_after = |kutta_lift: f64| {
        let mut sim = robot.instantiate().unwrap();
        for geom in ["wing_left", "wing_right"] {
            let c = sim.fluid_coefficients(geom).unwrap();
            sim.set_fluid_coefficients(geom, FluidCoefficients { kutta_lift, ..c }).unwrap();
        }
        sim.reset(&glide);
        sim.step(250).unwrap();
        sim.base_position_m().z
    };
    // Less Kutta lift, faster sink.
    let (paper, weak) = (altitude_after(3.14), altitude_after(1.0));
    assert!(paper > weak + 0.2, "altitude after 1 s: {paper} with C_K 3.14, {weak} with C_K 1.0");
}

#[test]
fn reset_sets_the_requested_state_and_readers_report_it() {
    let mut sim = RobotModel::flapper().unwrap().instantiate().unwrap();
    let initial = InitialState {
        position_m: Vec3::new(1.0, 2.0, 3.0),
        orientation: quat_from_euler(0.0, 0.0, std::f64::consts::FRAC_PI_2),
        linear_velocity_mps: Vec3::new(0.0, 3.8, 0.0),
        body_rates_radps: Vec3::new(0.1, -0.2, 0.3),
        joint_positions_rad: [0.1, -0.1, 0.2, -0.2, 0.05],
        joint_velocities_radps: [0.0; 5],
    };
    sim.reset(&initial);
    assert_eq!(sim.time_s(), 0.0);
    assert_eq!(sim.base_position_m(), initial.position_m);
    assert_eq!(sim.linear_velocity_mps(), initial.linear_velocity_mps);
    assert_eq!(sim.body_rates(), initial.body_rates_radps);
    assert_eq!(sim.joint_positions(), initial.joint_positions_rad);
    assert_eq!(sim.joint_targets(), initial.joint_positions_rad, "targets start where the joints are");
    // Flying along world +y while yawed 90 degrees: the pitot sees the full speed.
    assert!((sim.pitot_airspeed_mps() - 3.8).abs() < 1e-9);
    // A tail wind of 1 m/s lowers the airspeed by 1 m/s.
    sim.set_wind(Vec3::new(0.0, 1.0, 0.0)).unwrap();
    assert!((sim.pitot_airspeed_mps() - 2.8).abs() < 1e-9);
}

#[test]
fn joints_follow_their_targets_and_torques_respect_limits() {
    let mut sim = RobotModel::flapper().unwrap().instantiate().unwrap();
    let targets = [0.3, -0.2, 0.3, -0.2, -0.17];
    sim.set_joint_targets(&targets);
    sim.step(25).unwrap();
    let q = sim.joint_positions();
    for (joint, (q, t)) in ActuatedJoint::ALL.iter().zip(q.iter().zip(targets)) {
        assert!((q - t).abs() < 0.05, "{} at {q}, target {t}", joint.name());
    }
    let limits = [6.0, 1.0, 6.0, 1.0, 0.5];
    sim.set_joint_targets(&[1.0, 0.7, -1.0, -0.7, 0.6]);
    sim.step(1).unwrap();
    for (torque, limit) in sim.actuator_torques().iter().zip(limits) {
        assert!(torque.abs() <= limit + 1e-9, "{torque} beyond {limit}");
    }
}

#[test]
fn unphysical_numbers_in_a_model_are_refused_naming_them() {
    for (from, to, needle) in [
        ("timestep=\"0.004\"", "timestep=\"0\"", "timestep 0e0 s"),
        ("timestep=\"0.004\"", "timestep=\"1e300\"", "timestep 1e300 s"),
        ("density=\"1.225\"", "density=\"1e300\"", "density 1e300"),
        ("mass=\"0.226\"", "mass=\"1e300\"", "body 'main_body' has mass 1e300 kg"),
        ("damping=\"0.002\"", "damping=\"nan\"", "damping=\"nan\" is not a finite number"),
        ("mass=\"0.226\"", "mass=\"NaN\"", "mass=\"NaN\" is not a finite number"),
        ("mass=\"0.226\"", "mass=\"1e999\"", "mass=\"1e999\""),
        ("kp=\"40\"", "kp=\"nan\"", "line 42: kp=\"nan\""),
        ("range=\"-60 60\"", "range=\"10 60\"", "must be finite and contain 0"),
    ] {
        let text = flapper_sim::ROBOT_MJCF.replacen(from, to, 1);
        assert_ne!(text, flapper_sim::ROBOT_MJCF, "{from} is in the model");
        let err = RobotModel::from_mjcf(&text, "edited.xml").unwrap_err();
        assert!(err.to_string().contains(needle) && err.to_string().contains("edited.xml"), "{to}: {err}");
    }
}

#[test]
fn gravity_alone_accelerates_a_robot_in_vacuum_at_g() {
    // Physics invariant: with the air removed, the free base falls at 9.81 m/s^2.
    let robot = RobotModel::from_mjcf(
        &flapper_sim::ROBOT_MJCF.replace("density=\"1.225\"", "density=\"0\""),
        "flapper-in-vacuum",
    )
    .unwrap();
    let mut sim = robot.instantiate().unwrap();
    sim.step(250).unwrap();
    let vz = sim.linear_velocity_mps().z;
    assert!((vz + 9.81 * sim.time_s()).abs() < 0.02, "vz {vz} after {} s", sim.time_s());
}

#[test]
fn a_non_finite_target_is_a_fault_not_a_panic() {
    let mut sim = RobotModel::flapper().unwrap().instantiate().unwrap();
    sim.set_joint_targets(&[f64::NAN, 0.0, 0.0, 0.0, 0.0]);
    let fault = sim.step(5).unwrap_err();
    assert!(matches!(fault, SimFault::MujocoWarning { .. } | SimFault::NonFinite { .. }), "{fault}");
    // Reset clears the fault.
    sim.reset(&InitialState::default());
    sim.step(5).unwrap();
}

#[test]
fn an_exploding_state_is_a_fault() {
    let mut sim = RobotModel::flapper().unwrap().instantiate().unwrap();
    sim.reset(&InitialState { linear_velocity_mps: Vec3::new(1e30, 0.0, 0.0), ..InitialState::default() });
    assert!(sim.step(10).is_err());
}
