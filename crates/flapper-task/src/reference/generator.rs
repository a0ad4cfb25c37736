//! Paths from pieces. A [`Piece`] is a command held for a while (forward speed, vertical speed, yaw
//! rate: straight lines, climbs, dives and circular turns) or a vertical loop. [`build`] integrates
//! them into a [`Reference`]; [`procedural`] draws seeded pieces from a stage's ranges.

use std::f64::consts::{PI, TAU};

use flapper_sim::Vec3;
use rand::Rng;

use super::Reference;
use crate::config::ReferenceConfig;

/// Which vertical loop (all in the vertical plane of the current heading).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum LoopKind {
    /// Full loop pulling up (back-flip): returns to its start height, same heading.
    BackFlip,
    /// Half loop up then roll level: ends one diameter higher, heading reversed.
    Immelmann,
    /// Half loop pitching down then roll level: ends one diameter lower, heading reversed.
    RollOffTheBottom,
}

/// One piece of a path.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Piece {
    /// Hold forward (horizontal) speed, vertical speed and yaw rate for a duration.
    Command { forward_speed_mps: f64, vertical_speed_mps: f64, yaw_rate_radps: f64, duration_s: f64 },
    /// A vertical loop flown at constant speed.
    Loop { kind: LoopKind, speed_mps: f64, duration_s: f64 },
}

/// Integrates `pieces` from `start` with initial heading `yaw_rad`, sampling every `dt_s`.
pub fn build(name: &str, pieces: &[Piece], start: Vec3, yaw_rad: f64, dt_s: f64) -> Reference {
    let mut points = vec![start];
    let (mut position, mut yaw) = (start, yaw_rad);
    // Time carried between pieces so that samples stay exactly dt apart.
    let mut carry_s = 0.0;
    for piece in pieces {
        let duration = match *piece {
            Piece::Command { duration_s, .. } | Piece::Loop { duration_s, .. } => duration_s,
        };
        let heading = Vec3::new(yaw.cos(), yaw.sin(), 0.0);
        let piece_start = position;
        let at = |t: f64, yaw0: f64| -> (Vec3, f64) {
            match *piece {
                Piece::Command { forward_speed_mps: v, vertical_speed_mps: vz, yaw_rate_radps: r, .. } => {
                    let horizontal = if r.abs() < 1e-9 {
                        heading * v * t
                    } else {
                        // Circular arc: integral of v (cos, sin)(yaw0 + r s) ds.
                        let y1 = yaw0 + r * t;
                        Vec3::new((y1.sin() - yaw0.sin()) * v / r, (yaw0.cos() - y1.cos()) * v / r, 0.0)
                    };
                    (piece_start + horizontal + Vec3::Z * vz * t, yaw0 + r * t)
                }
                Piece::Loop { kind, speed_mps, duration_s } => {
                    let sweep = if kind == LoopKind::BackFlip { TAU } else { PI };
                    let radius = speed_mps * duration_s / sweep;
                    let angle = sweep * (t / duration_s).min(1.0);
                    let offset = match kind {
                        LoopKind::BackFlip | LoopKind::Immelmann => {
                            heading * radius * angle.sin() + Vec3::Z * radius * (1.0 - angle.cos())
                        }
                        LoopKind::RollOffTheBottom => {
                            heading * radius * angle.sin() - Vec3::Z * radius * (1.0 - angle.cos())
                        }
                    };
                    let yaw_after = if kind == LoopKind::BackFlip || t < duration_s { yaw0 } else { yaw0 + PI };
                    (piece_start + offset, yaw_after)
                }
            }
        };
        let mut t = dt_s - carry_s;
        while t <= duration + 1e-9 {
            points.push(at(t, yaw).0);
            t += dt_s;
        }
        carry_s = duration - (t - dt_s);
        let (end, end_yaw) = at(duration, yaw);
        position = end;
        yaw = match *piece {
            Piece::Loop { kind: LoopKind::Immelmann | LoopKind::RollOffTheBottom, .. } => yaw + PI,
            _ => end_yaw,
        };
    }
    Reference::new(name, dt_s, points)
}

/// A seeded random reference of at least `duration_s` (plus `extra_s` to cover the lookahead) from
/// a stage's ranges: one piece per slot, a loop with `loop_probability`, else a sharp turn with
/// `sharp_turn_probability`, else a straight descent at a glide slope with `glide_probability`, else a
/// long straight level command with `level_probability`, else a command held `command_duration_s` (at a
/// slow speed with `slow_probability`).
pub fn procedural(config: &ReferenceConfig, duration_s: f64, extra_s: f64, dt_s: f64, rng: &mut impl Rng) -> Reference {
    let mut pieces = Vec::new();
    let mut total = 0.0;
    let uniform =
        |rng: &mut dyn rand::RngCore, [lo, hi]: [f64; 2]| if hi > lo { rng.random_range(lo..=hi) } else { lo };
    // A chance drawn only where a config asks for it, so that configs without it keep their random streams.
    let chance = |rng: &mut dyn rand::RngCore, probability: f64| probability > 0.0 && rng.random_bool(probability);
    let cruise_speed = uniform(rng, config.forward_speed_mps);
    // Start with one held command so the launch is straight and level-ish.
    let mut first = true;
    while total < duration_s + extra_s {
        let speed = if first { cruise_speed } else { uniform(rng, config.forward_speed_mps) };
        let is_loop = !first && chance(rng, config.loop_probability);
        let is_sharp_turn = !first && !is_loop && chance(rng, config.sharp_turn_probability);
        let piece = if is_sharp_turn {
            let side = if rng.random_bool(0.5) { 1.0 } else { -1.0 };
            let angle = uniform(rng, config.sharp_turn_deg).to_radians() * side;
            let duration_s = uniform(rng, config.sharp_turn_duration_s);
            Piece::Command {
                forward_speed_mps: speed,
                vertical_speed_mps: 0.0,
                yaw_rate_radps: angle / duration_s,
                duration_s,
            }
        } else if is_loop {
            let kind = [LoopKind::BackFlip, LoopKind::Immelmann, LoopKind::RollOffTheBottom][rng.random_range(0..3)];
            let duration_s =
                if kind == LoopKind::BackFlip { config.loop_duration_s } else { 0.5 * config.loop_duration_s };
            Piece::Loop { kind, speed_mps: speed, duration_s }
        } else if !first && chance(rng, config.glide_probability) {
            let forward_speed_mps = uniform(rng, config.glide_speed_mps);
            Piece::Command {
                forward_speed_mps,
                vertical_speed_mps: -forward_speed_mps / uniform(rng, config.glide_ratio),
                yaw_rate_radps: 0.0,
                duration_s: config.command_duration_s,
            }
        } else if !first && chance(rng, config.level_probability) {
            Piece::Command {
                forward_speed_mps: uniform(rng, config.level_speed_mps),
                vertical_speed_mps: 0.0,
                yaw_rate_radps: 0.0,
                duration_s: config.level_duration_s,
            }
        } else {
            let slow = chance(rng, config.slow_probability);
            Piece::Command {
                forward_speed_mps: if slow { uniform(rng, config.slow_speed_mps) } else { speed },
                vertical_speed_mps: if first { 0.0 } else { uniform(rng, config.vertical_speed_mps) },
                yaw_rate_radps: if first { 0.0 } else { uniform(rng, config.yaw_rate_degps).to_radians() },
                duration_s: config.command_duration_s,
            }
        };
        total += match piece {
            Piece::Command { duration_s, .. } | Piece::Loop { duration_s, .. } => duration_s,
        };
        pieces.push(piece);
        first = false;
    }
    build("procedural", &pieces, Vec3::ZERO, 0.0, dt_s)
}
