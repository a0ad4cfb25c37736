//! Per-episode dynamics randomization (paper III-E, Table III), applied to one environment's own
//! model copy. Every draw starts from the nominal model, so nothing accumulates across episodes.

use flapper_sim::{ActuatedJoint, BODY_NAMES, FluidCoefficients, LIFTING_SURFACE_GEOMS, ModelError, Simulator, Vec3};
use rand::Rng;

use crate::config::{Interval, RandomizationConfig};

/// What was drawn for one episode (multipliers and offsets), for logs and tests.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct DrawnDynamics {
    pub joint_damping_scale: Vec<f64>,
    pub link_mass_scale: Vec<f64>,
    pub link_inertia_scale: Vec<f64>,
    pub link_com_offset_m: Vec<Vec3>,
    /// Per lifting surface, per coefficient.
    pub fluid_coefficient_scale: Vec<[f64; 5]>,
    pub added_mass_scale: Vec<f64>,
    pub added_inertia_scale: Vec<f64>,
    pub wind_mps: Vec3,
}

fn draw(rng: &mut impl Rng, [low, high]: Interval) -> f64 {
    if high > low { rng.random_range(low..=high) } else { low }
}

fn draw_symmetric(rng: &mut impl Rng, half_width: f64) -> f64 {
    draw(rng, [-half_width, half_width])
}

/// Restores the nominal model, then (if enabled) draws and applies new dynamics.
pub fn randomize(
    sim: &mut Simulator,
    config: &RandomizationConfig,
    rng: &mut impl Rng,
) -> Result<DrawnDynamics, ModelError> {
    sim.restore_nominal_parameters();
    let mut drawn = DrawnDynamics::default();
    if !config.enabled {
        return Ok(drawn);
    }
    // Drawn only for a fraction below 1, so the paper's setting keeps its random stream.
    if config.episode_fraction < 1.0 && !rng.random_bool(config.episode_fraction) {
        return Ok(drawn);
    }
    for joint in ActuatedJoint::ALL {
        let scale = draw(rng, config.joint_damping_scale);
        let damping = sim.joint_damping(joint.name())?;
        sim.set_joint_damping(joint.name(), damping * scale)?;
        drawn.joint_damping_scale.push(scale);
    }
    for body in BODY_NAMES {
        let (mass_scale, inertia_scale) = (draw(rng, config.link_mass_scale), draw(rng, config.link_inertia_scale));
        let offset = Vec3::new(
            draw_symmetric(rng, config.link_com_offset_m),
            draw_symmetric(rng, config.link_com_offset_m),
            draw_symmetric(rng, config.link_com_offset_m),
        );
        sim.set_body_mass(body, sim.body_mass(body)? * mass_scale)?;
        sim.set_body_inertia(body, sim.body_inertia(body)?.map(|i| i * inertia_scale))?;
        sim.set_body_com(body, sim.body_com(body)? + offset)?;
        drawn.link_mass_scale.push(mass_scale);
        drawn.link_inertia_scale.push(inertia_scale);
        drawn.link_com_offset_m.push(offset);
    }
    for geom in LIFTING_SURFACE_GEOMS {
        // All five are drawn whichever are applied, so the random stream does not depend on the choice.
        let drawn_scales: [f64; 5] = std::array::from_fn(|_| draw(rng, config.fluid_coefficient_scale));
        let scales: [f64; 5] =
            std::array::from_fn(|i| if config.fluid_coefficients_randomized[i] { drawn_scales[i] } else { 1.0 });
        let nominal = sim.fluid_coefficients(geom)?.to_array();
        sim.set_fluid_coefficients(
            geom,
            FluidCoefficients::from_array(std::array::from_fn(|i| nominal[i] * scales[i])),
        )?;
        let (mass_scale, inertia_scale) = (draw(rng, config.added_mass_scale), draw(rng, config.added_inertia_scale));
        sim.set_added_mass(geom, sim.added_mass(geom)?.map(|m| m * mass_scale))?;
        sim.set_added_inertia(geom, sim.added_inertia(geom)?.map(|i| i * inertia_scale))?;
        drawn.fluid_coefficient_scale.push(scales);
        drawn.added_mass_scale.push(mass_scale);
        drawn.added_inertia_scale.push(inertia_scale);
    }
    let [wx, wy, wz] = config.wind_mps;
    let [sx, sy, sz] = config.steady_wind_mps;
    drawn.wind_mps =
        Vec3::new(sx + draw_symmetric(rng, wx), sy + draw_symmetric(rng, wy), sz + draw_symmetric(rng, wz));
    sim.set_wind(drawn.wind_mps)?;
    Ok(drawn)
}
