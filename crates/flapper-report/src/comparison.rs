//! The "paper vs flapper" table: the paper's numbers ([`paper`]) beside ours, read from the report
//! run's results ([`RunResults`]). Each of our numbers also names where it lies in the run's files (a
//! JSON pointer into one), so anyone (and a test, through [`Source::read`]) can check the page
//! against the files.

use std::path::Path;

use flapper_analysis::modes::SegmentFigures;
use flapper_analysis::robustness::RobustnessReport;
use flapper_analysis::sysid::{AXES, AxisModel};
use flapper_eval::tracking_report::TrackingSummary;
use serde_json::Value;

use crate::results::{ROBUSTNESS_REFERENCES, RunResults, files};
use crate::{ReportError, paper};

/// How a source's value is printed.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Format {
    /// Fixed point with this many decimals.
    Fixed(usize),
    /// Scientific with this many decimals.
    Scientific(usize),
    /// `yes` / `no`.
    YesNo,
    /// A string as it is.
    Text,
}

impl Format {
    /// `x` printed in this format; `None` for the formats that are not numbers.
    fn number(self, x: f64) -> Option<String> {
        match self {
            Format::Fixed(d) => Some(format!("{x:.d$}")),
            Format::Scientific(d) => Some(format!("{x:.d$e}")),
            Format::YesNo | Format::Text => None,
        }
    }
}

/// One number of a row: `file` (relative to the report folder), a JSON pointer into it, a scale
/// applied before formatting, and the format.
#[derive(Debug, Clone, PartialEq)]
pub struct Source {
    pub file: String,
    pub pointer: String,
    pub scale: f64,
    pub format: Format,
}

impl Source {
    fn new(file: &str, pointer: &str, scale: f64, format: Format) -> Self {
        Self { file: file.to_owned(), pointer: pointer.to_owned(), scale, format }
    }

    /// The value in the report folder `out`, formatted; `None` if the file or the key is missing.
    pub fn read(&self, out: &Path) -> Option<String> {
        let text = std::fs::read_to_string(out.join(&self.file)).ok()?;
        let json: Value = serde_json::from_str(&text).ok()?;
        let value = json.pointer(&self.pointer)?;
        Some(match self.format {
            Format::Fixed(_) | Format::Scientific(_) => self.format.number(value.as_f64()? * self.scale)?,
            Format::YesNo => {
                if value.as_bool()? {
                    "yes".into()
                } else {
                    "no".into()
                }
            }
            Format::Text => value.as_str()?.to_owned(),
        })
    }

    /// `file#pointer*scale:format`, as written in the CSV.
    pub fn describe(&self) -> String {
        let format = match self.format {
            Format::Fixed(d) => format!("f{d}"),
            Format::Scientific(d) => format!("e{d}"),
            Format::YesNo => "yesno".into(),
            Format::Text => "text".into(),
        };
        format!("{}#{}*{}:{format}", self.file, self.pointer, self.scale)
    }

    /// Reads back [`Source::describe`].
    pub fn parse(text: &str) -> Option<Self> {
        let (file, rest) = text.split_once('#')?;
        let (pointer, rest) = rest.rsplit_once('*')?;
        let (scale, format) = rest.split_once(':')?;
        let format = match format {
            "yesno" => Format::YesNo,
            "text" => Format::Text,
            f if f.starts_with('f') => Format::Fixed(f[1..].parse().ok()?),
            f if f.starts_with('e') => Format::Scientific(f[1..].parse().ok()?),
            _ => return None,
        };
        Some(Self { file: file.to_owned(), pointer: pointer.to_owned(), scale: scale.parse().ok()?, format })
    }
}

/// One claim of the paper beside ours: a row of `paper_vs_flapper.csv`.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct Row {
    pub claim: String,
    pub paper: String,
    /// Our figures, each the formatted value of a source.
    pub flapper: String,
    pub verdict: String,
    /// In the file: space-separated descriptions ([`Source::describe`]).
    #[serde(serialize_with = "described")]
    pub sources: Vec<Source>,
}

fn described<S: serde::Serializer>(sources: &[Source], serializer: S) -> Result<S::Ok, S::Error> {
    serializer.collect_str(&sources.iter().map(Source::describe).collect::<Vec<_>>().join(" "))
}

/// One of our numbers: its value, formatted (None where it was not measured), and where it lies in
/// the run's files (for the CSV, and for anyone checking the page against the files).
struct Figure {
    source: Source,
    value: Option<String>,
}

impl Figure {
    fn number(file: &str, pointer: &str, value: Option<f64>, scale: f64, format: Format) -> Self {
        let value = value.filter(|v| v.is_finite()).and_then(|v| format.number(v * scale));
        Self { source: Source::new(file, pointer, scale, format), value }
    }

    fn yes_no(file: &str, pointer: &str, value: Option<bool>) -> Self {
        let value = value.map(|yes| if yes { "yes".to_owned() } else { "no".to_owned() });
        Self { source: Source::new(file, pointer, 1.0, Format::YesNo), value }
    }

    fn text(file: &str, pointer: &str, value: Option<&str>) -> Self {
        Self { source: Source::new(file, pointer, 1.0, Format::Text), value: value.map(str::to_owned) }
    }
}

/// The table being built from a report run's results.
struct Table<'a> {
    results: &'a RunResults,
    rows: Vec<Row>,
}

impl Table<'_> {
    /// Adds a row whose text `text` makes from its figures' values when every figure was measured;
    /// otherwise the row says "not measured".
    fn row(&mut self, claim: &str, paper: &str, figures: Vec<Figure>, text: &dyn Fn(&[String]) -> (String, String)) {
        let values: Option<Vec<String>> = figures.iter().map(|f| f.value.clone()).collect();
        let (flapper, verdict) = match values {
            Some(v) => text(&v),
            None => ("not measured".into(), "-".into()),
        };
        let sources = figures.into_iter().map(|f| f.source).collect();
        self.rows.push(Row { claim: claim.into(), paper: paper.into(), flapper, verdict, sources });
    }
}

/// What the paper says beside what a report run measured.
pub fn compare(results: &RunResults) -> Vec<Row> {
    let mut table = Table { results, rows: Vec::new() };
    for add in [gait, flight_modes, identification, manoeuvres, training_cost, robustness, phase_portraits] {
        add(&mut table);
    }
    table.rows
}

/// The learned gait: flapping frequency and the energy in its fundamental.
fn gait(table: &mut Table) {
    let (file, cruise) = (files::tracking("cruise"), table.results.tracking("cruise"));
    // Flap, wing pitch and tail: one figure each of the cruise summary's `key`.
    let per_joint = |key: &str, of: fn(&TrackingSummary) -> [f64; 3], scale: f64, decimals: usize| -> Vec<Figure> {
        (0..3)
            .map(|k| {
                let value = cruise.map(|s| of(s)[k]);
                Figure::number(&file, &format!("/summary/{key}/{k}"), value, scale, Format::Fixed(decimals))
            })
            .collect()
    };
    let paper_hz = paper::FLAP_FREQUENCY_HZ;
    table.row(
        "learned flapping frequency (cruise at 3.8 m/s)",
        &format!("{paper_hz} Hz"),
        per_joint("frequency_hz", |s| s.frequency_hz, 1.0, 2),
        &|v| {
            let flap: f64 = v[0].parse().unwrap_or(f64::NAN);
            let off = 100.0 * (flap / paper_hz - 1.0);
            (
                format!("{} / {} / {} Hz (flap / wing pitch / tail)", v[0], v[1], v[2]),
                if off.abs() <= 10.0 {
                    format!("agrees within 10% (flap {off:+.0}%)")
                } else {
                    format!("differs: flap {off:+.0}%")
                },
            )
        },
    );
    let (lowest, highest) = paper::FUNDAMENTAL_ENERGY_PERCENT;
    table.row(
        "energy in the fundamental frequency",
        &format!("{lowest}-{highest}% (flap, wing pitch, tail)"),
        per_joint("energy_fraction", |s| s.energy_fraction, 100.0, 1),
        &|v| {
            let within = v.iter().all(|x| x.parse::<f64>().is_ok_and(|p| (30.0..=45.0).contains(&p)));
            (
                format!("{}% / {}% / {}%", v[0], v[1], v[2]),
                if within { "agrees (30-45%)".into() } else { "differs".into() },
            )
        },
    );
}

/// Flight modes: gliding where the path allows it, and level flight at the speed of the paper's phase
/// portraits.
fn flight_modes(table: &mut Table) {
    let segment = |k: usize, key: &str, of: fn(&SegmentFigures) -> f64, decimals: usize| {
        let value = table.results.modes.as_ref().and_then(|m| m.segments.get(k)).map(of);
        Figure::number(files::MODES, &format!("/segments/{k}/{key}"), value, 1.0, Format::Fixed(decimals))
    };
    let figures = vec![
        segment(2, "glide_fraction", |s| s.glide_fraction, 2),
        segment(3, "glide_fraction", |s| s.glide_fraction, 2),
        segment(2, "flap_amplitude_deg", |s| s.flap_amplitude_deg, 0),
        segment(0, "flap_amplitude_deg", |s| s.flap_amplitude_deg, 0),
    ];
    table.row(
        "switches between flight modes: glides when possible (glide segment of longitudinal)",
        "glides instead of flapping when possible",
        figures,
        &|v| {
            let glides = v[0].parse::<f64>().is_ok_and(|f| f >= 0.5);
            (
                format!(
                    "wings held {} of the glide segment, {} of the dive; flap amplitude {} deg gliding vs {} deg in cruise",
                    v[0], v[1], v[2], v[3]
                ),
                if glides { "agrees (glide fraction >= 0.5)".into() } else { "differs: flaps through the glide".into() },
            )
        },
    );
    let slowest = table
        .results
        .robustness(ROBUSTNESS_REFERENCES[0])
        .and_then(|r| r.envelope.as_ref())
        .and_then(|e| e.slowest_sustained_mps);
    table.row(
        "level flight at 3 m/s (the phase portraits' speed)",
        "flown",
        vec![Figure::number(
            &files::robustness(ROBUSTNESS_REFERENCES[0]),
            "/envelope/slowest_sustained_mps",
            slowest,
            1.0,
            Format::Fixed(1),
        )],
        &|v| {
            let slow_enough = v[0].parse::<f64>().is_ok_and(|s| s <= 3.0);
            (
                format!("slowest level flight completed in >= 90% of episodes: {} m/s", v[0]),
                if slow_enough { "agrees".into() } else { format!("differs: not below {} m/s", v[0]) },
            )
        },
    );
}

/// The identified closed loop: its error, poles and zeros.
fn identification(table: &mut Table) {
    let axes = table.results.sysid.as_ref().map(|s| s.per_axis.each());
    let axis = |k: usize| axes.map(|a| a[k].1);
    let number = |k: usize, key: &str, of: fn(&AxisModel) -> f64, format: Format| {
        Figure::number(files::SYSID, &format!("/{}/{key}", AXES[k]), axis(k).map(of), 1.0, format)
    };
    let paper_mse = paper::IDENTIFICATION_MSE_M2;
    table.row(
        "identification MSE of the closed loop",
        &format!("{paper_mse:.1e} m^2"),
        (0..3).map(|k| number(k, "mse_validation", |m| m.mse_validation, Format::Scientific(1))).collect(),
        &|v| {
            let worst = v.iter().filter_map(|x| x.parse::<f64>().ok()).fold(0.0, f64::max);
            (
                format!("x {} / y {} / z {} m^2", v[0], v[1], v[2]),
                if worst <= 1e-4 {
                    "agrees".into()
                } else {
                    format!("higher: up to {:.0}x the paper's", worst / paper_mse)
                },
            )
        },
    );
    table.row(
        "identified model's fit to validation flights (input: the target point ahead, lead estimated)",
        "not reported (input: the current desired position)",
        (0..3)
            .flat_map(|k| {
                [
                    number(k, "fit_percent", |m| m.fit_percent, Format::Fixed(1)),
                    number(k, "input_lead_s", |m| m.input_lead_s, Format::Fixed(2)),
                ]
            })
            .collect(),
        &|v| {
            let worst = [&v[0], &v[2], &v[4]].iter().filter_map(|x| x.parse::<f64>().ok()).fold(100.0, f64::min);
            (
                format!("x {}% ({} s ahead) / y {}% ({} s) / z {}% ({} s)", v[0], v[1], v[2], v[3], v[4], v[5]),
                if worst >= 80.0 { "predicts the flight".into() } else { format!("weak: {worst:.0}% on one axis") },
            )
        },
    );
    type Verdict = fn(&AxisModel) -> bool;
    let verdicts: [(&str, &str, Verdict); 2] = [
        ("closed-loop poles in the left half plane (BIBO stable)", "bibo_stable", |m| m.bibo_stable),
        ("zeros in the left half plane (minimum phase)", "minimum_phase", |m| m.minimum_phase),
    ];
    for (claim, key, of) in verdicts {
        table.row(
            claim,
            "yes, every axis",
            (0..3).map(|k| Figure::yes_no(files::SYSID, &format!("/{}/{key}", AXES[k]), axis(k).map(of))).collect(),
            &|v| {
                (
                    format!("x {}, y {}, z {}", v[0], v[1], v[2]),
                    if v.iter().all(|x| x == "yes") { "agrees".into() } else { "differs".into() },
                )
            },
        );
    }
}

/// The manoeuvres of Figs. 10-11, flown.
fn manoeuvres(table: &mut Table) {
    for (name, claim) in [
        ("sharp-turn", "180 deg turn in 1.2 s"),
        ("loop", "loop in 3 s"),
        ("roll-off-the-bottom", "roll-off-the-bottom in 1.8 s"),
        ("aerobatic", "aerobatic trajectory"),
    ] {
        let (file, summary) = (files::tracking(name), table.results.tracking(name));
        let count = |pointer: &str, of: fn(&TrackingSummary) -> usize| {
            Figure::number(&file, pointer, summary.map(|s| of(s) as f64), 1.0, Format::Fixed(0))
        };
        let mut figures =
            vec![count("/summary/completed", |s| s.completed), count("/summary/episodes", |s| s.episodes)];
        let manoeuvre = name != "aerobatic";
        figures.push(if manoeuvre {
            let value = summary.and_then(|s| s.manoeuvre.as_ref()).map(|m| m.mean_max_error_m);
            Figure::number(&file, "/summary/manoeuvre/mean_max_error_m", value, 1.0, Format::Fixed(2))
        } else {
            let value = summary.map(|s| s.mean_rms_error_m);
            Figure::number(&file, "/summary/mean_rms_error_m", value, 1.0, Format::Fixed(2))
        });
        table.row(claim, "flown, tracking the reference", figures, &|v| {
            let (done, of): (f64, f64) = (v[0].parse().unwrap_or(0.0), v[1].parse().unwrap_or(1.0));
            let detail = if manoeuvre {
                format!("largest error in it {} m (mean)", v[2])
            } else {
                format!("RMS error {} m", v[2])
            };
            (
                format!("completed {}/{}; {detail}", v[0], v[1]),
                if done >= 0.9 * of { "agrees".into() } else { format!("partly: {:.0}% completed", 100.0 * done / of) },
            )
        });
    }
}

/// What training cost.
fn training_cost(table: &mut Table) {
    let training = table.results.training.as_ref();
    table.row(
        "training cost",
        &paper::training_cost(),
        vec![
            Figure::number(
                files::TRAINING,
                "/total_env_steps",
                training.map(|t| t.total_env_steps),
                1e-6,
                Format::Fixed(1),
            ),
            Figure::number(
                files::TRAINING,
                "/total_wall_time_s",
                training.map(|t| t.total_wall_time_s),
                1.0 / 3600.0,
                Format::Fixed(2),
            ),
        ],
        &|v| {
            let (steps, hours): (f64, f64) = (v[0].parse().unwrap_or(0.0), v[1].parse().unwrap_or(0.0));
            let paper_rate = paper::TRAINING_ENV_STEPS_MILLIONS / paper::TRAINING_HOURS;
            let ratio = if hours > 0.0 { (steps / hours) / paper_rate } else { f64::NAN };
            (
                format!("{} M steps in {} h (the whole curriculum, validation included)", v[0], v[1]),
                format!("{ratio:.1}x the paper's steps per hour"),
            )
        },
    );
}

/// Robustness to the fluid coefficients and to Table III at once.
fn robustness(table: &mut Table) {
    let swept: Vec<(&str, &RobustnessReport)> =
        ROBUSTNESS_REFERENCES.iter().filter_map(|&r| Some((r, table.results.robustness(r)?))).collect();
    // All five coefficients at once, at the widest range flown.
    let widest_all = |report: &RobustnessReport| {
        report
            .fluid
            .iter()
            .enumerate()
            .filter(|(_, f)| f.coefficient == "all")
            .max_by(|a, b| a.1.range.total_cmp(&b.1.range))
            .map(|(k, f)| (k, f.tally.success_rate))
    };
    let figures: Vec<Figure> = swept
        .iter()
        .filter_map(|(r, report)| {
            let (k, rate) = widest_all(report)?;
            Some(Figure::number(
                &files::robustness(r),
                &format!("/fluid/{k}/success_rate"),
                Some(rate),
                100.0,
                Format::Fixed(0),
            ))
        })
        .collect();
    table.row(
        "success with all five fluid coefficients randomized x[0.5, 1.5]",
        "relatively successful (Fig. 9)",
        figures,
        &|v| {
            let text =
                v.iter().zip(ROBUSTNESS_REFERENCES).map(|(x, r)| format!("{r} {x}%")).collect::<Vec<_>>().join(", ");
            let ok = v.len() == 2 && v.iter().all(|x| x.parse::<f64>().is_ok_and(|p| p >= 80.0));
            (text, if ok { "agrees (>= 80%)".into() } else { "partly: below 80% somewhere".into() })
        },
    );
    table.row(
        "most sensitive fluid coefficient",
        "Kutta lift C_K",
        ROBUSTNESS_REFERENCES
            .iter()
            .map(|&r| {
                let value = table.results.robustness(r).and_then(|j| j.most_sensitive_coefficient.as_deref());
                Figure::text(&files::robustness(r), "/most_sensitive_coefficient", value)
            })
            .collect(),
        &|v| {
            (
                format!("longitudinal {}, lateral {}", v[0], v[1]),
                if v.iter().all(|x| x == "kutta") {
                    "agrees".into()
                } else if v.iter().any(|x| x == "kutta") {
                    "partly".into()
                } else {
                    "differs".into()
                },
            )
        },
    );
    table.row(
        "everything in Table III randomized at once",
        "tracks (Fig. 8)",
        ROBUSTNESS_REFERENCES
            .iter()
            .map(|&r| {
                let value = table.results.robustness(r).and_then(|j| j.table_iii).map(|t| t.success_rate);
                Figure::number(&files::robustness(r), "/table_iii/success_rate", value, 100.0, Format::Fixed(0))
            })
            .collect(),
        &|v| {
            let ok = v.iter().all(|x| x.parse::<f64>().is_ok_and(|p| p >= 90.0));
            (
                format!("success longitudinal {}%, lateral {}%", v[0], v[1]),
                if ok { "agrees (>= 90%)".into() } else { "partly: below 90%".into() },
            )
        },
    );
}

/// The phase portraits' claims, one row each, as `flapper phase` checks them.
fn phase_portraits(table: &mut Table) {
    let claims = table.results.phase.as_ref().map(|p| p.claims.as_slice()).unwrap_or_default();
    for (k, claim) in claims.iter().enumerate() {
        table.row(
            &format!("phase portrait (Fig. 6-7): {}", claim.claim),
            "as stated",
            vec![
                Figure::text(files::PHASE, &format!("/claims/{k}/ours"), Some(&claim.ours)),
                Figure::yes_no(files::PHASE, &format!("/claims/{k}/confirmed"), Some(claim.confirmed)),
            ],
            &|v| {
                (
                    format!("{} (confirmed: {})", v[0], v[1]),
                    if v[1] == "yes" { "agrees".into() } else { "differs".into() },
                )
            },
        );
    }
}

/// `paper_vs_flapper.csv`: claim, paper, flapper, verdict, sources (space-separated descriptions).
pub fn write_csv(rows: &[Row], path: &Path) -> Result<(), ReportError> {
    flapper_files::write_csv_records(path, rows)
        .map_err(|e| ReportError::Write { path: path.to_owned(), message: e.to_string() })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_source_reads_formats_and_round_trips() {
        let dir = std::env::temp_dir().join(format!("flapper-comparison-{}", std::process::id()));
        std::fs::create_dir_all(dir.join("a")).unwrap();
        std::fs::write(dir.join("a/b.json"), r#"{"x": [0.5, 2.0], "ok": true, "name": "kutta"}"#).unwrap();
        let s = Source::new("a/b.json", "/x/0", 100.0, Format::Fixed(1));
        assert_eq!(s.read(&dir).as_deref(), Some("50.0"));
        assert_eq!(Source::parse(&s.describe()), Some(s));
        assert_eq!(Source::new("a/b.json", "/x/1", 1.0, Format::Scientific(1)).read(&dir).as_deref(), Some("2.0e0"));
        assert_eq!(Source::new("a/b.json", "/ok", 1.0, Format::YesNo).read(&dir).as_deref(), Some("yes"));
        assert_eq!(Source::new("a/b.json", "/name", 1.0, Format::Text).read(&dir).as_deref(), Some("kutta"));
        assert_eq!(Source::new("a/b.json", "/missing", 1.0, Format::Text).read(&dir), None);
        assert_eq!(Source::new("a/none.json", "/x", 1.0, Format::Text).read(&dir), None);
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
