//! Reference paths: named shapes, seeded generation, CSV validation.

use flapper_sim::Vec3;
use flapper_task::config::{ReferenceConfig, TaskConfig};
use flapper_task::reference::csv_file::parse_reference_csv;
use flapper_task::reference::generator::procedural;
use flapper_task::reference::named::{named, reference_names};
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;

const DT: f64 = 0.02;

fn heading_deg(reference: &flapper_task::reference::Reference, step: usize) -> f64 {
    let d = reference.direction(step);
    d.y.atan2(d.x).to_degrees()
}

#[test]
fn every_named_reference_exists_and_moves() {
    for name in reference_names() {
        let r = named(name, Vec3::ZERO, DT, 0.0).unwrap_or_else(|| panic!("{name} missing"));
        assert!(r.duration_s() > 5.0, "{name}: {} s", r.duration_s());
        assert!(r.points().iter().all(|p| p.is_finite()));
        for k in 0..r.len() - 1 {
            assert!(r.speed(k) < 6.0, "{name}: {:.2} m/s at step {k}", r.speed(k));
        }
    }
    assert!(named("barrel-roll", Vec3::ZERO, DT, 0.0).is_none());
}

#[test]
fn longitudinal_and_lateral_have_the_papers_durations_and_speeds() {
    let lon = named("longitudinal", Vec3::ZERO, DT, 0.0).unwrap();
    assert!((lon.duration_s() - 24.0).abs() < 0.03, "{}", lon.duration_s());
    let horizontal =
        |r: &flapper_task::reference::Reference, k: usize| (r.target(k + 1) - r.target(k)).truncate().length() / DT;
    assert!((horizontal(&lon, 100) - 3.8).abs() < 1e-9);
    // Climb during the second 6 s, descend during the last 12 s.
    assert!(lon.target(600).z - lon.target(300).z > 2.0);
    assert!(lon.target(1199).z < lon.target(600).z - 5.0);
    let lat = named("lateral", Vec3::ZERO, DT, 0.0).unwrap();
    assert!((lat.duration_s() - 18.0).abs() < 0.03);
    assert!((horizontal(&lat, 10) - 5.3).abs() < 1e-9);
    assert!(lat.points().iter().all(|p| p.z.abs() < 1e-9), "lateral stays level");
}

#[test]
fn a_loop_returns_to_its_start_height_and_heading() {
    let r = named("loop", Vec3::new(0.0, 0.0, 10.0), DT, 0.0).unwrap();
    let (before, after) = (150, 300); // loop from 3 s to 6 s
    assert!(
        (r.target(after).z - r.target(before).z).abs() < 0.02,
        "height {} vs {}",
        r.target(after).z,
        r.target(before).z
    );
    let top = r.points()[before..after].iter().map(|p| p.z).fold(f64::MIN, f64::max);
    assert!(top - 10.0 > 3.0, "loop top only {:.2} m up", top - 10.0);
    assert!(heading_deg(&r, after + 5).abs() < 1.0);
}

#[test]
fn a_sharp_turn_reverses_heading_within_1_2_seconds() {
    let r = named("sharp-turn", Vec3::ZERO, DT, 0.0).unwrap();
    assert!(heading_deg(&r, 140).abs() < 1.0);
    let after = heading_deg(&r, 150 + 61).abs();
    assert!((after - 180.0).abs() < 1.0, "heading {after} deg after 1.2 s");
}

#[test]
fn immelmann_climbs_and_roll_off_the_bottom_descends_both_reversing() {
    let up = named("immelmann", Vec3::ZERO, DT, 0.0).unwrap();
    let down = named("roll-off-the-bottom", Vec3::ZERO, DT, 0.0).unwrap();
    let end = 150 + 90 + 10;
    assert!(up.target(end).z > 3.0 && down.target(end).z < -3.0);
    assert!((heading_deg(&up, end).abs() - 180.0).abs() < 1.0);
    assert!((heading_deg(&down, end).abs() - 180.0).abs() < 1.0);
}

#[test]
fn procedural_references_are_seeded_and_follow_the_stage() {
    let stage2 = TaskConfig::stage(2).unwrap().reference;
    let make = |seed| procedural(&stage2, 30.0, 0.62, DT, &mut ChaCha8Rng::seed_from_u64(seed));
    assert_eq!(make(7), make(7));
    assert_ne!(make(7), make(8));
    assert!(make(7).duration_s() >= 30.6);
    let stage1 = procedural(&ReferenceConfig::default(), 30.0, 0.62, DT, &mut ChaCha8Rng::seed_from_u64(1));
    assert!(stage1.points().iter().all(|p| p.y.abs() < 1e-9 && p.z.abs() < 1e-9), "stage 1 flies straight and level");
    assert!((stage1.speed(100) - 3.8).abs() < 1e-9);
    // Stage 2 climbs or dives after the first 3 s command.
    let r = make(3);
    let vertical: f64 = (150..1500).map(|k| (r.target(k + 1).z - r.target(k).z).abs()).sum();
    assert!(vertical > 1.0);
}

#[test]
fn slow_commands_take_their_share_and_change_nothing_where_not_asked_for() {
    let fast = ReferenceConfig { forward_speed_mps: [4.5, 5.0], ..ReferenceConfig::default() };
    let make = |config: &ReferenceConfig| procedural(config, 60.0, 0.62, DT, &mut ChaCha8Rng::seed_from_u64(5));
    // Probability 0 draws nothing extra: the same path whatever the slow range says.
    assert_eq!(make(&fast), make(&ReferenceConfig { slow_speed_mps: [1.0, 1.5], ..fast.clone() }));
    let always = ReferenceConfig { slow_probability: 1.0, slow_speed_mps: [2.5, 3.0], ..fast.clone() };
    let [slowest, fastest] = make(&always).speed_range_mps();
    assert!(slowest >= 2.5 - 1e-6 && fastest <= 3.0 + 1e-6, "every command slow: {slowest}..{fastest} m/s");
    // Half the commands slow: both ranges are flown within one minute of commands.
    let half = make(&ReferenceConfig { slow_probability: 0.5, ..always.clone() });
    let speeds: Vec<f64> = (0..half.len() - 1).step_by(150).map(|k| half.speed(k)).collect();
    assert!(speeds.iter().any(|&v| v < 3.05) && speeds.iter().any(|&v| v > 4.45), "{speeds:?}");
}

#[test]
fn glide_commands_descend_straight_at_their_slope_and_change_nothing_where_not_asked_for() {
    let stage3 = TaskConfig::stage(3).unwrap().reference;
    let make = |config: &ReferenceConfig| procedural(config, 60.0, 0.62, DT, &mut ChaCha8Rng::seed_from_u64(5));
    // Probability 0 draws nothing extra: the same path whatever the glide ranges say.
    assert_eq!(
        make(&stage3),
        make(&ReferenceConfig { glide_speed_mps: [1.0, 1.5], glide_ratio: [9.0, 9.5], ..stage3.clone() })
    );
    let always = ReferenceConfig {
        glide_probability: 1.0,
        glide_speed_mps: [3.6, 4.0],
        glide_ratio: [4.0, 4.5],
        loop_probability: 0.0,
        sharp_turn_probability: 0.0,
        ..stage3.clone()
    };
    let r = make(&always);
    // After the first (level) command every step descends straight ahead at a glide slope.
    let first = (always.command_duration_s / DT) as usize + 1;
    for k in (first..r.len() - 1).step_by(10) {
        let step = r.target(k + 1) - r.target(k);
        let horizontal = (step.x * step.x + step.y * step.y).sqrt();
        let ratio = horizontal / -step.z;
        assert!((4.0 - 1e-6..=4.5 + 1e-6).contains(&ratio), "step {k}: glide ratio {ratio}");
        assert!((3.6 - 1e-6..=4.0 + 1e-6).contains(&(horizontal / DT)), "step {k}: {} m/s", horizontal / DT);
        assert!(step.y.abs() < 1e-9, "step {k}: glides fly straight");
    }
    // A share of them: some commands glide, the others keep the stage's ranges (turns among them).
    let some = make(&ReferenceConfig { glide_probability: 0.4, ..always.clone() });
    let gliding = (first..some.len() - 1)
        .step_by(150)
        .filter(|&k| {
            let step = some.target(k + 1) - some.target(k);
            let ratio = (step.x * step.x + step.y * step.y).sqrt() / -step.z;
            (4.0 - 1e-6..=4.5 + 1e-6).contains(&ratio)
        })
        .count();
    let commands = (first..some.len() - 1).step_by(150).count();
    assert!(gliding > 0 && gliding < commands, "{gliding} of {commands} commands glide");
}

#[test]
fn level_commands_fly_straight_and_level_for_their_duration_and_change_nothing_where_not_asked_for() {
    let stage3 = TaskConfig::stage(3).unwrap().reference;
    let make = |config: &ReferenceConfig| procedural(config, 60.0, 0.62, DT, &mut ChaCha8Rng::seed_from_u64(7));
    assert_eq!(
        make(&stage3),
        make(&ReferenceConfig { level_speed_mps: [1.0, 1.5], level_duration_s: 20.0, ..stage3.clone() }),
        "probability 0 draws nothing extra"
    );
    let always = ReferenceConfig {
        level_probability: 1.0,
        level_speed_mps: [2.6, 2.9],
        level_duration_s: 9.0,
        loop_probability: 0.0,
        sharp_turn_probability: 0.0,
        ..stage3.clone()
    };
    let r = make(&always);
    // After the first command every step flies straight and level at a level speed, for 9 s each.
    let first = (always.command_duration_s / DT) as usize + 1;
    let heading = |k: usize| {
        let step = r.target(k + 1) - r.target(k);
        step.y.atan2(step.x)
    };
    for k in (first..r.len() - 1).step_by(10) {
        let step = r.target(k + 1) - r.target(k);
        assert!(step.z.abs() < 1e-9, "step {k}: level");
        let speed = (step.x * step.x + step.y * step.y).sqrt() / DT;
        assert!((2.6 - 1e-6..=2.9 + 1e-6).contains(&speed), "step {k}: {speed} m/s");
    }
    let within_first_level_command = first + 10..first + (9.0 / DT) as usize - 10;
    let straight = within_first_level_command.clone().all(|k| (heading(k) - heading(first + 10)).abs() < 1e-9);
    assert!(straight, "one level command holds its heading for its 9 s");
    assert!(r.duration_s() >= 60.0 && r.duration_s() < 60.0 + 0.62 + 9.0 + DT, "{} s", r.duration_s());
}

#[test]
fn csv_reference_loads_and_resamples() {
    let text = "time_s,x_m,y_m,z_m\n0,0,0,10\n0.5,2,0,10\n1.0,4,0,10.5\n";
    let r = parse_reference_csv(text, "mine.csv", DT, 30).unwrap();
    assert_eq!(r.len(), 51);
    assert!((r.target(25) - Vec3::new(2.0, 0.0, 10.0)).length() < 1e-9);
    assert!((r.target(50) - Vec3::new(4.0, 0.0, 10.5)).length() < 1e-9);
}

#[test]
fn csv_columns_are_read_by_name_in_any_order() {
    let ordered = "time_s,x_m,y_m,z_m\n0,0,0,10\n0.5,2,1,10\n1.0,4,2,10.5\n";
    let shuffled = "x_m,y_m,z_m,time_s\n0,0,10,0\n2,1,10,0.5\n4,2,10.5,1.0\n";
    let (a, b) = (
        parse_reference_csv(ordered, "a.csv", DT, 30).unwrap(),
        parse_reference_csv(shuffled, "b.csv", DT, 30).unwrap(),
    );
    assert_eq!(a.points(), b.points());
    assert!((b.target(50) - Vec3::new(4.0, 2.0, 10.5)).length() < 1e-9);
}

#[test]
fn bad_csv_references_are_rejected_naming_the_line() {
    let check = |text: &str, needles: &[&str]| {
        let err = parse_reference_csv(text, "path.csv", DT, 30).unwrap_err().to_string();
        for needle in needles {
            assert!(err.contains(needle), "'{needle}' not in: {err}");
        }
    };
    check("time_s,x_m,y_m,z_m\n0,0,0,0\n0.5,1,0,0\n0.5,2,0,0\n", &["path.csv", "line 4", "does not increase"]);
    check("time_s,x_m,y_m,z_m\n0,0,0,0\n0.5,nan,0,0\n1.0,2,0,0\n", &["line 3", "not finite"]);
    check("time_s,x_m,y_m,z_m\n0,0,0,0\n0.5,abc,0,0\n", &["line 3", "'abc' is not a number"]);
    check("time_s,x_m,y_m,z_m\n0,0,0,0\n0.5,50,0,0\n1.0,51,0,0\n", &["line 3", "m/s"]);
    check("time_s,x_m,y_m,z_m\n0,0,0,0\n0.3,1,0,0\n", &["0.300 s", "lookahead"]);
    check("time_s,x_m,y_m,z_m\n0,0,0\n", &["line 2", "4 columns"]);
    check("time_s,x_m,y_m,z_m\n", &["no data rows"]);
    // Columns are read by their names, never by position.
    check("x_m,y_m,z_m,time\n0,0,10,0\n", &["line 1", "unknown column 'time'", "time_s,x_m,y_m,z_m"]);
    check("x_m,y_m,z_m\n0,0,10\n", &["line 1", "no column 'time_s'"]);
    check("time_s,x_m,y_m,z_m,z_m\n0,0,0,0,0\n", &["line 1", "names 'z_m' twice"]);
    // No header: the first row would be lost silently if taken for one.
    check("0,0,0,10\n1,3.8,0,10\n2,7.6,0,10\n", &["line 1", "is data, not a header"]);
    // A constant far-away coordinate (zero speed) and a reference that would need a billion points.
    check("time_s,x_m,y_m,z_m\n0,1e300,0,0\n1,1e300,0,0\n", &["line 2", "beyond"]);
    check("time_s,x_m,y_m,z_m\n0,0,0,10\n999999,0,0,10\n", &["covers 999999 s", "at most 3600"]);
}

#[test]
fn resolve_finds_names_and_files_and_lists_the_names_when_it_cannot() {
    use flapper_task::reference::{NAMED_START_M, resolve};
    let loop_ref = resolve("loop", 0.02, 30).unwrap();
    assert_eq!(loop_ref.points()[0], NAMED_START_M);
    assert_eq!(loop_ref.dt_s(), 0.02);
    let error = resolve("corkscrew", 0.02, 30).unwrap_err().to_string();
    assert!(error.contains("unknown reference 'corkscrew'") && error.contains("aerobatic"), "{error}");
    let path = std::env::temp_dir().join(format!("flapper-resolve-{}.csv", std::process::id()));
    std::fs::write(&path, "time_s,x_m,y_m,z_m\n0,0,0,5\n2,8,0,5\n").unwrap();
    let from_file = resolve(path.to_str().unwrap(), 0.02, 30).unwrap();
    std::fs::remove_file(&path).unwrap();
    assert_eq!(from_file.len(), 101);
    assert!(resolve("/nowhere/path.csv", 0.02, 30).unwrap_err().to_string().contains("/nowhere/path.csv"));
}

#[test]
fn the_fastest_turn_is_zero_on_straight_paths_and_the_circles_rate_on_a_circle() {
    // A straight climb at 20 deg, speed changing: no turn.
    let climb: Vec<Vec3> = (0..200)
        .map(|k| {
            let s = 0.02 * k as f64 * (3.0 + 0.01 * k as f64);
            Vec3::new(s * 20f64.to_radians().cos(), 0.0, s * 20f64.to_radians().sin())
        })
        .collect();
    let climb = flapper_task::reference::Reference::new("climb", DT, climb);
    assert!(climb.fastest_turn_degps(0, 150) < 1e-3, "{}", climb.fastest_turn_degps(0, 150));
    // Straight for 1 s, then a vertical circle at 90 deg/s: the window sees the turn only once it reaches it.
    let rate = 90f64.to_radians();
    let (speed, radius) = (3.8, 3.8 / rate);
    let mut points: Vec<Vec3> = (0..50).map(|k| Vec3::new(speed * DT * k as f64, 0.0, 0.0)).collect();
    let start = *points.last().unwrap();
    points.extend((1..200).map(|k| {
        let angle = rate * DT * k as f64;
        start + Vec3::new(radius * angle.sin(), 0.0, radius * (1.0 - angle.cos()))
    }));
    let circle = flapper_task::reference::Reference::new("circle", DT, points);
    assert!(circle.fastest_turn_degps(0, 30) < 1e-3, "straight ahead for the whole window");
    let on_circle = circle.fastest_turn_degps(60, 30);
    assert!((on_circle - 90.0).abs() < 0.5, "{on_circle}");
    assert!((circle.fastest_turn_degps(30, 30) - 90.0).abs() < 0.5, "the window reaches the circle");
    // The named loop turns 360 deg in 3 s; its cruise before does not turn.
    let looping = named("loop", Vec3::ZERO, DT, 0.0).unwrap();
    assert!(looping.fastest_turn_degps(0, 30) < 1e-3);
    let fastest = looping.fastest_turn_degps(0, looping.len());
    assert!((110.0..200.0).contains(&fastest), "{fastest}");
}
