//! The references of the paper's results, selectable by name. Durations and speeds follow the paper
//! (IV-C and its figures); where the paper shows a path but gives no numbers, ours are stated here.

use flapper_sim::Vec3;

use super::Reference;
use super::generator::{LoopKind, Piece, build};

/// Every name [`named`] knows, with what it is.
pub const NAMED_REFERENCES: [(&str, &str); 8] = [
    ("cruise", "30 s straight and level at 3.8 m/s"),
    ("longitudinal", "cruise, climb (+0.8 m/s), glide (-0.83 m/s), dive (-1.5 m/s): 6 s each, 24 s at 3.8 m/s"),
    ("lateral", "gradual left turn (20 deg/s, 90 deg) and quick right turn (60 deg/s, 180 deg): 18 s at 5.3 m/s"),
    ("loop", "3 s cruise, a back-flip loop in 3 s, 3 s cruise, at 3.8 m/s"),
    ("sharp-turn", "3 s cruise, 180 deg turn in 1.2 s, 3 s cruise, at 3.8 m/s"),
    ("roll-off-the-bottom", "3 s cruise, half loop pitching down in 1.8 s, 3 s cruise, at 3.8 m/s"),
    ("immelmann", "3 s cruise, half loop up in 1.8 s, 3 s cruise, at 3.8 m/s"),
    ("aerobatic", "loop, turns and roll-off-the-bottom joined by cruising and recovery (about 26 s)"),
];

const CRUISE_MPS: f64 = flapper_sim::CRUISE_SPEED_MPS;

fn cruise(duration_s: f64, speed: f64) -> Piece {
    Piece::Command { forward_speed_mps: speed, vertical_speed_mps: 0.0, yaw_rate_radps: 0.0, duration_s }
}

fn turn(degrees: f64, duration_s: f64, speed: f64) -> Piece {
    Piece::Command {
        forward_speed_mps: speed,
        vertical_speed_mps: 0.0,
        yaw_rate_radps: degrees.to_radians() / duration_s,
        duration_s,
    }
}

fn vertical(vertical_speed_mps: f64, duration_s: f64) -> Piece {
    Piece::Command { forward_speed_mps: CRUISE_MPS, vertical_speed_mps, yaw_rate_radps: 0.0, duration_s }
}

/// The pieces of a named reference, or `None` for an unknown name.
pub fn named_pieces(name: &str) -> Option<Vec<Piece>> {
    let v = CRUISE_MPS;
    let pieces = match name {
        "cruise" => vec![cruise(30.0, v)],
        "longitudinal" => vec![cruise(6.0, v), vertical(0.8, 6.0), vertical(-0.83, 6.0), vertical(-1.5, 6.0)],
        "lateral" => {
            let fast = 5.3;
            vec![
                cruise(3.0, fast),
                turn(90.0, 4.5, fast),
                cruise(3.0, fast),
                turn(-180.0, 3.0, fast),
                cruise(4.5, fast),
            ]
        }
        "loop" => vec![
            cruise(3.0, v),
            Piece::Loop { kind: LoopKind::BackFlip, speed_mps: v, duration_s: 3.0 },
            cruise(3.0, v),
        ],
        "sharp-turn" => vec![cruise(3.0, v), turn(180.0, 1.2, v), cruise(3.0, v)],
        "roll-off-the-bottom" => vec![
            cruise(3.0, v),
            Piece::Loop { kind: LoopKind::RollOffTheBottom, speed_mps: v, duration_s: 1.8 },
            cruise(3.0, v),
        ],
        "immelmann" => {
            vec![
                cruise(3.0, v),
                Piece::Loop { kind: LoopKind::Immelmann, speed_mps: v, duration_s: 1.8 },
                cruise(3.0, v),
            ]
        }
        "aerobatic" => vec![
            cruise(3.0, v),
            Piece::Loop { kind: LoopKind::BackFlip, speed_mps: v, duration_s: 3.0 },
            cruise(3.0, v),
            turn(90.0, 3.0, v),
            cruise(2.0, v),
            turn(-180.0, 1.2, v),
            cruise(3.0, v),
            Piece::Loop { kind: LoopKind::RollOffTheBottom, speed_mps: v, duration_s: 1.8 },
            cruise(6.0, v),
        ],
        _ => return None,
    };
    Some(pieces)
}

/// The pieces of a named reference as labelled spans of time (s from its start): `cruise`, `climb`,
/// `descent`, `turn left`, `turn right`, `loop`, `immelmann`, `roll-off-the-bottom`. For drawing a
/// path coloured by manoeuvre; `None` for an unknown name.
pub fn piece_spans(name: &str) -> Option<Vec<(&'static str, f64, f64)>> {
    let mut start = 0.0;
    let spans = named_pieces(name)?
        .iter()
        .map(|piece| {
            let (label, duration) = match *piece {
                Piece::Command { vertical_speed_mps, yaw_rate_radps, duration_s, .. } => {
                    let label = if yaw_rate_radps > 0.0 {
                        "turn left"
                    } else if yaw_rate_radps < 0.0 {
                        "turn right"
                    } else if vertical_speed_mps > 0.0 {
                        "climb"
                    } else if vertical_speed_mps < 0.0 {
                        "descent"
                    } else {
                        "cruise"
                    };
                    (label, duration_s)
                }
                Piece::Loop { kind, duration_s, .. } => match kind {
                    LoopKind::BackFlip => ("loop", duration_s),
                    LoopKind::Immelmann => ("immelmann", duration_s),
                    LoopKind::RollOffTheBottom => ("roll-off-the-bottom", duration_s),
                },
            };
            start += duration;
            (label, start - duration, start)
        })
        .collect();
    Some(spans)
}

/// When the manoeuvre of a named reference happens: from the start of its first piece that is not
/// straight and level to the end of its last one (s from the reference's start); `None` for a
/// reference that is straight and level throughout, one that ends inside its manoeuvre (no cruise
/// after it to rejoin, as `longitudinal`'s dive), or an unknown name.
pub fn manoeuvre_window_s(name: &str) -> Option<(f64, f64)> {
    let pieces = named_pieces(name)?;
    let is_cruise = |p: &Piece| matches!(p, Piece::Command { vertical_speed_mps, yaw_rate_radps, .. } if *vertical_speed_mps == 0.0 && *yaw_rate_radps == 0.0);
    let duration = |p: &Piece| match p {
        Piece::Command { duration_s, .. } | Piece::Loop { duration_s, .. } => *duration_s,
    };
    let first = pieces.iter().position(|p| !is_cruise(p))?;
    let last = pieces.iter().rposition(|p| !is_cruise(p))?;
    if last + 1 == pieces.len() {
        return None;
    }
    let start: f64 = pieces[..first].iter().map(duration).sum();
    let end: f64 = pieces[..=last].iter().map(duration).sum();
    Some((start, end))
}

/// A named reference starting at `start` heading along +x, sampled every `dt_s`, followed by
/// `extra_s` of straight flight at the final speed so the lookahead never runs off the end.
pub fn named(name: &str, start: Vec3, dt_s: f64, extra_s: f64) -> Option<Reference> {
    let mut pieces = named_pieces(name)?;
    let final_speed = match pieces.last() {
        Some(Piece::Command { forward_speed_mps, .. }) => *forward_speed_mps,
        Some(Piece::Loop { speed_mps, .. }) => *speed_mps,
        None => CRUISE_MPS,
    };
    if extra_s > 0.0 {
        pieces.push(cruise(extra_s, final_speed));
    }
    Some(build(name, &pieces, start, 0.0, dt_s))
}

/// The names, for help texts and error messages.
pub fn reference_names() -> Vec<&'static str> {
    NAMED_REFERENCES.iter().map(|(name, _)| *name).collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn piece_spans_tile_the_reference_in_order() {
        let spans = piece_spans("aerobatic").unwrap();
        let labels: Vec<&str> = spans.iter().map(|s| s.0).collect();
        assert_eq!(
            labels,
            [
                "cruise",
                "loop",
                "cruise",
                "turn left",
                "cruise",
                "turn right",
                "cruise",
                "roll-off-the-bottom",
                "cruise"
            ]
        );
        assert_eq!(spans[0].1, 0.0);
        for pair in spans.windows(2) {
            assert_eq!(pair[0].2, pair[1].1);
        }
        let reference = named("aerobatic", Vec3::ZERO, 0.02, 0.0).unwrap();
        assert!((spans.last().unwrap().2 - reference.duration_s()).abs() < 0.02);
        assert_eq!(
            piece_spans("longitudinal").unwrap().iter().map(|s| s.0).collect::<Vec<_>>(),
            ["cruise", "climb", "descent", "descent"]
        );
        assert!(piece_spans("no-such-reference").is_none());
    }
}
