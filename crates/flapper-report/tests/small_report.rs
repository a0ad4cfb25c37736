//! A small report end to end (one episode per reference and per robustness setting, small pictures):
//! every figure of the paper is present, non-empty and on the page, and every number of the
//! paper-vs-flapper table is the value in the file and key its row names.

use std::path::{Path, PathBuf};

use flapper_report::comparison::Source;
use flapper_report::results::RunResults;
use flapper_report::{ReportSettings, generate};

fn repository() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../..")
}

/// The files behind the paper's figures (Fig. 1-3, 5-11), the learning curves and the energy frontier.
const FIGURES: [&str; 18] = [
    "tracking/cruise/joints.svg",
    "sysid/pole_zero.svg",
    "sysid/bode.svg",
    "sysid/validation.svg",
    "phase/phase_climb.svg",
    "phase/phase_turn.svg",
    "tracking/longitudinal/path.svg",
    "tracking/lateral/path.svg",
    "robustness/longitudinal/robustness_wind.svg",
    "robustness/lateral/robustness_wind.svg",
    "robustness/longitudinal/robustness_fluid.svg",
    "robustness/lateral/robustness_fluid.svg",
    "render/aerobatic_manoeuvres.svg",
    "modes/modes.svg",
    "training/stage1_learning_curves.svg",
    "training/stage3_learning_curves.svg",
    "frontier/energy_vs_tracking.svg",
    "frontier/energy_vs_slow_flight.svg",
];
const PICTURES: [&str; 6] = [
    "render/robot.png",
    "render/loop.png",
    "render/sharp-turn.png",
    "render/roll-off-the-bottom.png",
    "render/aerobatic_poster.png",
    "render/aerobatic.mp4",
];

#[test]
fn a_small_report_has_every_figure_and_reads_its_numbers_from_its_files() {
    let robot = flapper_sim::RobotModel::flapper().unwrap();
    let root = repository();
    let out = std::env::temp_dir().join(format!("flapper-small-report-{}", std::process::id()));
    std::fs::create_dir_all(&out).unwrap();
    let settings = ReportSettings {
        policy: root.join("policies/history/stage3/policy.safetensors"),
        curriculum: root.join("policies/final"),
        episodes: 1,
        robustness_episodes: 1,
        seed: 3,
        pictures: true,
        video_size_px: (320, 180),
        snapshot_size_px: (320, 180),
        sysid: flapper_analysis::sysid::SysidSettings { averaged_periods: 2, ..Default::default() },
    };
    let outcome = generate(&robot, &settings, &out, &|_| {}).unwrap();
    let html = std::fs::read_to_string(&outcome.index_html).unwrap();
    let markdown = std::fs::read_to_string(&outcome.report_md).unwrap();

    // Pictures need EGL (and the video ffmpeg): where they cannot be made, the report says why.
    let can_render = flapper_render::FlightRenderer::new(&robot, 16, 16).is_ok();
    let mut expected: Vec<&str> = FIGURES.to_vec();
    if can_render && flapper_render::ffmpeg_available() {
        expected.extend(PICTURES);
    } else {
        assert!(!outcome.notes.is_empty(), "pictures missing without a note saying why");
    }
    for figure in expected {
        let path = out.join(figure);
        let size = std::fs::metadata(&path).map(|m| m.len()).unwrap_or(0);
        assert!(size > 0, "{figure} is missing or empty");
        // src= of an image or a video, or a video's poster=.
        assert!(html.contains(&format!("=\"{figure}\"")), "{figure} is not on index.html");
        assert!(markdown.contains(figure), "{figure} is not in report.md");
    }
    // Nothing on the page points at a file that is not there.
    for attribute in ["src=\"", "poster=\""] {
        for src in html.split(attribute).skip(1).map(|rest| &rest[..rest.find('"').unwrap()]) {
            assert!(out.join(src).is_file(), "index.html shows '{src}', which was not written");
        }
    }

    // The comparison: each number of the flapper column is its source's value.
    let mut reader = csv::Reader::from_path(out.join("paper_vs_flapper.csv")).unwrap();
    let mut rows = 0;
    for record in reader.records() {
        let record = record.unwrap();
        let (claim, flapper, sources) = (&record[0], &record[2], &record[4]);
        assert_ne!(flapper, "not measured", "{claim}");
        assert!(
            html.contains(
                &flapper.replace('&', "&amp;").replace('<', "&lt;").replace('>', "&gt;").replace('"', "&quot;")
            ),
            "{claim}: not on the page"
        );
        assert!(!sources.is_empty(), "{claim} names no source");
        for description in sources.split(' ') {
            let source = Source::parse(description).unwrap_or_else(|| panic!("{claim}: bad source '{description}'"));
            let value =
                source.read(&out).unwrap_or_else(|| panic!("{claim}: '{description}' is not in the run's files"));
            assert!(flapper.contains(&value), "{claim}: '{flapper}' does not show {value} from {description}");
        }
        rows += 1;
    }
    assert!(rows >= 14, "only {rows} comparisons");

    // Every result file reads back as the type that wrote it (NaN written as null included).
    let results = RunResults::read(&out);
    assert_eq!(
        results.tracking.len(),
        flapper_report::TRACKED_REFERENCES.len(),
        "a tracking summary does not read back"
    );
    assert_eq!(results.robustness.len(), 2, "a robustness.json does not read back");
    assert!(
        results.sysid.is_some() && results.phase.is_some() && results.modes.is_some(),
        "an analysis does not read back"
    );
    assert!(results.tables.is_some() && results.training.is_some(), "the tables do not read back");
    // The frontier: the report's own controller first (here not the final one), every shipped controller
    // and the scripted gait measured with the report's episodes, then the points of
    // docs/energy-frontier.csv, each with its source.
    let frontier = results.frontier.expect("frontier.csv reads back");
    let measured: Vec<&str> =
        frontier.iter().filter(|r| r.longitudinal_episodes == Some(1)).map(|r| r.label.as_str()).collect();
    let mut expected = vec![settings.policy.display().to_string(), "final".to_owned()];
    let mut experiments: Vec<String> = std::fs::read_dir(root.join("policies/experiments"))
        .unwrap()
        .map(|e| e.unwrap())
        .filter(|e| e.path().join("policy.safetensors").is_file())
        .map(|e| e.file_name().to_string_lossy().into_owned())
        .collect();
    experiments.sort();
    expected.extend(experiments);
    expected.extend(["six stages", "previous final", "previous stage-4 lineage", "scripted gait"].map(String::from));
    assert_eq!(measured, expected);
    let points = flapper_analysis::frontier::file::read_frontier_csv(&root.join("docs/energy-frontier.csv")).unwrap();
    assert_eq!(frontier[measured.len()..], points[..], "the points follow the measured rows");
    assert_eq!(frontier[measured.len() - 1].energy_ratio, Some(1.0));
    assert!(html.contains("Energy against tracking") && html.contains("efficient-bird bars"), "no frontier section");
    std::fs::remove_dir_all(&out).unwrap();
}
