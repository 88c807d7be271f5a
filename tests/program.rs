//! Robot programs: every format read back by a small parser of its own
//! (angles in the format's units, order, measure/via marks, waits), and
//! the inputs and options the writers refuse.

use robokrige::compensate::{CommandsOutput, CompensationOptions, compensate};
use robokrige::kinematics;
use robokrige::kriging::{KrigingOptions, OptimizerKind};
use robokrige::model::ErrorModel;
use robokrige::program::{
    ProgramFormat, ProgramOptions, ProgramPose, check_robot, program_name, render, write,
};
use robokrige::space::Space;
use robokrige::trajectory::{TargetFile, Trajectory, read_target_file};
use std::path::Path;

const TOL: f64 = 1e-9;

/// One move as a parser reads it back: joints in the format's units, the
/// measurement index (`None` for a via-point), the label, the wait after it.
#[derive(Debug, PartialEq)]
struct Move {
    q: Vec<f64>,
    measure: Option<usize>,
    label: Option<String>,
    wait_s: Option<f64>,
}

/// Eight six-joint poses with awkward decimals and signs: via-points
/// first and in between, measured poses, labels on some.
fn poses() -> Vec<ProgramPose> {
    (0..8)
        .map(|i| {
            let q: Vec<f64> = (0..6)
                .map(|j| 170.0 * ((i * 6 + j) as f64 * 0.731 + 0.1).sin() + 1e-7 * j as f64)
                .collect();
            let p = if i % 3 == 0 {
                ProgramPose::via(q)
            } else {
                ProgramPose::measured(q)
            };
            match i {
                0 => p.with_label("pre-position"),
                4 => p.with_label("P 17"),
                _ => p,
            }
        })
        .collect()
}

/// `(measure index, label)` of a mark comment: `measure k (label)` or
/// `via (label)`.
fn parse_mark(text: &str) -> (Option<usize>, Option<String>) {
    let (head, label) = match text.split_once(" (") {
        Some((h, l)) => (
            h,
            Some(l.strip_suffix(')').expect("label in ( )").to_string()),
        ),
        None => (text, None),
    };
    let measure = match head.strip_prefix("measure ") {
        Some(k) => Some(k.parse().expect("measure index")),
        None => {
            assert_eq!(head, "via", "mark {text:?}");
            None
        }
    };
    (measure, label)
}

fn numbers(list: &str, sep: char) -> Vec<f64> {
    list.split(sep)
        .map(|v| v.trim().parse().unwrap_or_else(|_| panic!("number {v:?}")))
        .collect()
}

/// The moves of a program's body: a mark comment (after `comment`), then
/// the move (`parse_move`), then optionally a wait (`parse_wait`). Lines
/// that are none of these must be `skip`ped by the caller's predicate.
fn parse_body(
    lines: &[&str],
    comment: &str,
    parse_move: impl Fn(&str) -> Option<Vec<f64>>,
    parse_wait: impl Fn(&str) -> Option<f64>,
    skip: impl Fn(&str) -> bool,
) -> Vec<Move> {
    let mut moves: Vec<Move> = Vec::new();
    let mut mark: Option<(Option<usize>, Option<String>)> = None;
    for line in lines.iter().map(|l| l.trim()) {
        if let Some(c) = line.strip_prefix(comment) {
            let c = c.trim();
            if c.starts_with("written by robokrige") {
                continue;
            }
            assert!(mark.is_none(), "two marks in a row at {line:?}");
            mark = Some(parse_mark(c));
        } else if let Some(q) = parse_move(line) {
            let (measure, label) = mark.take().expect("a move without its mark");
            moves.push(Move {
                q,
                measure,
                label,
                wait_s: None,
            });
        } else if let Some(t) = parse_wait(line) {
            let last = moves.last_mut().expect("a wait before any move");
            assert!(last.wait_s.is_none(), "two waits after a move");
            last.wait_s = Some(t);
        } else {
            assert!(skip(line), "unexpected line {line:?}");
        }
    }
    assert!(mark.is_none(), "a mark without its move");
    moves
}

fn parse_urscript(text: &str) -> (String, Vec<Move>) {
    let lines: Vec<&str> = text.lines().collect();
    let name = lines[0]
        .strip_prefix("def ")
        .and_then(|l| l.strip_suffix("():"))
        .expect("def NAME():");
    assert_eq!(*lines.last().unwrap(), "end");
    let moves = parse_body(
        &lines[1..lines.len() - 1],
        "#",
        |l| {
            let inner = l.strip_prefix("movej([")?;
            let (list, rest) = inner.split_once("], ")?;
            assert_eq!(rest, "a=0.5, v=0.25)", "{l}");
            Some(numbers(list, ','))
        },
        |l| l.strip_prefix("sleep(")?.strip_suffix(')')?.parse().ok(),
        |_| false,
    );
    (name.to_string(), moves)
}

fn parse_krl(text: &str) -> (String, Vec<Move>) {
    let lines: Vec<&str> = text.lines().collect();
    let name = lines[0]
        .strip_prefix("DEF ")
        .and_then(|l| l.strip_suffix("( )"))
        .expect("DEF NAME( )");
    assert_eq!(*lines.last().unwrap(), "END");
    let moves = parse_body(
        &lines[1..lines.len() - 1],
        ";",
        |l| {
            let inner = l.strip_prefix("PTP {")?.strip_suffix('}')?;
            let q = inner.split(", ").enumerate().map(|(k, axis)| {
                let (a, v) = axis.split_once(' ').expect("axis value");
                assert_eq!(a, format!("A{}", k + 1));
                v.parse::<f64>().expect("axis value")
            });
            Some(q.collect())
        },
        |l| l.strip_prefix("WAIT SEC ")?.parse().ok(),
        |l| l.starts_with("$VEL_AXIS[") || l.starts_with("$ACC_AXIS["),
    );
    (name.to_string(), moves)
}

fn parse_rapid(text: &str) -> (String, Vec<Move>) {
    let lines: Vec<&str> = text.lines().collect();
    let name = lines[0].strip_prefix("MODULE ").expect("MODULE NAME");
    assert_eq!(lines[lines.len() - 2..], ["  ENDPROC", "ENDMODULE"]);
    let moves = parse_body(
        &lines[1..lines.len() - 2],
        "!",
        |l| {
            let inner = l.strip_prefix("MoveAbsJ [[")?;
            let (robax, rest) = inner.split_once("],[")?;
            assert_eq!(rest, "9E9,9E9,9E9,9E9,9E9,9E9]], v100, fine, tool0;", "{l}");
            Some(numbers(robax, ','))
        },
        |l| l.strip_prefix("WaitTime ")?.strip_suffix(';')?.parse().ok(),
        |l| l == "PROC main()",
    );
    (name.to_string(), moves)
}

fn parse_csv(text: &str) -> Vec<Move> {
    let mut lines = text.lines();
    let header: Vec<&str> = lines.next().unwrap().split(',').collect();
    assert_eq!(header[0], "id");
    let n = header.iter().filter(|h| h.starts_with('q')).count();
    let q_names: Vec<String> = (1..=n).map(|k| format!("q{k}")).collect();
    assert_eq!(header[1..=n], q_names);
    assert_eq!(header[n + 1..], ["measure", "label"]);
    let mut measured = 0;
    lines
        .enumerate()
        .map(|(i, l)| {
            let cells: Vec<&str> = l.split(',').collect();
            assert_eq!(cells[0], i.to_string());
            let measure = match cells[n + 1] {
                "1" => {
                    measured += 1;
                    Some(measured - 1)
                }
                "0" => None,
                m => panic!("measure {m:?}"),
            };
            Move {
                q: numbers(&cells[1..=n].join(","), ','),
                measure,
                label: Some(cells[n + 2])
                    .filter(|s| !s.is_empty())
                    .map(String::from),
                wait_s: None,
            }
        })
        .collect()
}

/// `moves` are `poses` in order, joints converted by `unit` to 1e-9, with
/// measure indices counted along the measured poses and a wait of
/// `wait_s` after each measured pose.
fn assert_round_trip(
    moves: &[Move],
    poses: &[ProgramPose],
    unit: fn(f64) -> f64,
    wait_s: Option<f64>,
) {
    assert_eq!(moves.len(), poses.len());
    let mut measured = 0;
    for (i, (m, p)) in moves.iter().zip(poses).enumerate() {
        assert_eq!(m.q.len(), p.q.len(), "move {i}");
        for (a, b) in m.q.iter().zip(&p.q) {
            assert!((a - unit(*b)).abs() < TOL, "move {i}: {a} vs {}", unit(*b));
        }
        let expected = p.measure.then(|| {
            measured += 1;
            measured - 1
        });
        assert_eq!(m.measure, expected, "move {i}");
        assert_eq!(m.label, p.label, "move {i}");
        assert_eq!(m.wait_s, wait_s.filter(|_| p.measure), "move {i}");
    }
}

fn same(v: f64) -> f64 {
    v
}

#[test]
fn urscript_round_trips_radians_order_marks_and_waits() {
    let p = poses();
    let text = render(&p, ProgramFormat::Urscript, &ProgramOptions::default()).unwrap();
    let (name, moves) = parse_urscript(&text);
    assert_eq!(name, "robokrige_plan");
    assert_round_trip(&moves, &p, f64::to_radians, Some(2.0));
}

#[test]
fn krl_round_trips_degrees_order_marks_and_waits() {
    let p = poses();
    let opts = ProgramOptions {
        name: "campaign_1".into(),
        settle_s: 3.5,
        ..ProgramOptions::default()
    };
    let text = render(&p, ProgramFormat::Krl, &opts).unwrap();
    let (name, moves) = parse_krl(&text);
    assert_eq!(name, "campaign_1");
    assert_round_trip(&moves, &p, same, Some(3.5));
    for k in 1..=6 {
        assert!(
            text.contains(&format!("  $VEL_AXIS[{k}] = 20.0\n")),
            "{text}"
        );
    }
}

#[test]
fn rapid_round_trips_degrees_order_marks_and_waits() {
    let p = poses();
    let text = render(&p, ProgramFormat::Rapid, &ProgramOptions::default()).unwrap();
    let (name, moves) = parse_rapid(&text);
    assert_eq!(name, "robokrige_plan");
    assert_round_trip(&moves, &p, same, Some(2.0));
}

#[test]
fn csv_round_trips_joints_order_marks_and_labels_exactly() {
    let p = poses();
    let text = render(&p, ProgramFormat::Csv, &ProgramOptions::default()).unwrap();
    let moves = parse_csv(&text);
    assert_round_trip(&moves, &p, same, None);
    for (m, pose) in moves.iter().zip(&p) {
        assert_eq!(m.q, pose.q, "full precision");
    }
    // a program of other joint counts (a SCARA) is fine as CSV, without a
    // label column when no pose has a label
    let scara = vec![ProgramPose::measured(vec![10.0, -20.0, 150.5, 30.0])];
    let text = render(&scara, ProgramFormat::Csv, &ProgramOptions::default()).unwrap();
    assert_eq!(text, "id,q1,q2,q3,q4,measure\n0,10,-20,150.5,30,1\n");
}

#[test]
fn a_program_csv_reads_back_as_a_pose_list() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("plan.csv");
    let p = poses();
    write(&path, &p, ProgramFormat::Csv, &ProgramOptions::default()).unwrap();
    let TargetFile::Joints(data) = read_target_file(&path).unwrap() else {
        panic!("not read as joint poses");
    };
    assert_eq!(data.q, p.iter().map(|p| p.q.clone()).collect::<Vec<_>>());
    let measure = &data.covariate("measure").expect("measure column").values;
    let flags: Vec<f64> = p.iter().map(|p| f64::from(u8::from(p.measure))).collect();
    assert_eq!(measure, &flags);
    assert!(data.warnings().is_empty(), "{:?}", data.warnings());
}

#[test]
fn no_settle_time_writes_no_waits() {
    let p = poses();
    let opts = ProgramOptions {
        settle_s: 0.0,
        ..ProgramOptions::default()
    };
    let text = render(&p, ProgramFormat::Urscript, &opts).unwrap();
    assert_round_trip(&parse_urscript(&text).1, &p, f64::to_radians, None);
    let text = render(&p, ProgramFormat::Krl, &opts).unwrap();
    assert_round_trip(&parse_krl(&text).1, &p, same, None);
    let text = render(&p, ProgramFormat::Rapid, &opts).unwrap();
    assert_round_trip(&parse_rapid(&text).1, &p, same, None);
}

fn err(poses: &[ProgramPose], format: ProgramFormat, opts: &ProgramOptions) -> String {
    render(poses, format, opts).unwrap_err().to_string()
}

#[test]
fn bad_poses_are_refused_with_the_pose_and_joint_named() {
    let o = ProgramOptions::default();
    for f in ProgramFormat::ALL {
        let e = err(&[], f, &o);
        assert!(e.contains("no poses to write"), "{e}");
        let mut p = poses();
        p[3].q[1] = f64::NAN;
        let e = err(&p, f, &o);
        assert!(
            e.contains("pose 3 (0-based), joint q2: NaN is not a finite"),
            "{e}"
        );
        let mut p = poses();
        p[5].q[0] = f64::INFINITY;
        let e = err(&p, f, &o);
        assert!(e.contains("pose 5 (0-based), joint q1: inf"), "{e}");
        let mut p = poses();
        p[2].q.pop();
        let e = err(&p, f, &o);
        assert!(
            e.contains("pose 2 (0-based) has 5 joint values but pose 0 has 6"),
            "{e}"
        );
        let mut p = poses();
        p[1].label = Some("two\nlines".into());
        let e = err(&p, f, &o);
        assert!(
            e.contains("pose 1 (0-based): label") && e.contains("printable ASCII"),
            "{e}"
        );
        let e = err(&[ProgramPose::via(Vec::new())], f, &o);
        assert!(e.contains("pose 0 has no joint values"), "{e}");
    }
}

#[test]
fn controllers_refuse_robots_they_cannot_program() {
    let o = ProgramOptions::default();
    let scara = vec![ProgramPose::via(vec![10.0, -20.0, 150.0, 30.0])];
    for f in [
        ProgramFormat::Urscript,
        ProgramFormat::Krl,
        ProgramFormat::Rapid,
    ] {
        let e = err(&scara, f, &o);
        assert!(e.contains("4") && e.contains("--format csv"), "{f:?}: {e}");
    }
    let seven = vec![ProgramPose::via(vec![0.0; 7])];
    let e = err(&seven, ProgramFormat::Krl, &o);
    assert!(
        e.starts_with("KRL program: written for six-axis robots only"),
        "{e}"
    );
    let with_slide = ProgramOptions {
        prismatic: vec![false, false, true, false, false, false],
        ..ProgramOptions::default()
    };
    let e = err(&poses(), ProgramFormat::Urscript, &with_slide);
    assert!(e.contains("joint q3 is prismatic"), "{e}");
    // KRL and RAPID take a linear axis in mm, and say so
    for f in [ProgramFormat::Krl, ProgramFormat::Rapid] {
        let text = render(&poses(), f, &with_slide).unwrap();
        assert!(text.contains("joints in deg (mm for q3)\n"), "{text}");
        let text = render(&poses(), f, &ProgramOptions::default()).unwrap();
        assert!(text.contains("joints in deg\n"), "{text}");
    }
    let e = err(
        &poses(),
        ProgramFormat::Krl,
        &ProgramOptions {
            prismatic: vec![false; 4],
            ..ProgramOptions::default()
        },
    );
    assert!(
        e.contains("4 prismatic-joint flags for poses of 6 joints"),
        "{e}"
    );
    let e = check_robot(ProgramFormat::Urscript, &[false, false, true, false])
        .unwrap_err()
        .to_string();
    assert!(
        e.starts_with("URScript program: movej takes the 6 joints"),
        "{e}"
    );
    assert!(check_robot(ProgramFormat::Csv, &[false, false, true, false]).is_ok());
}

#[test]
fn bad_options_are_refused() {
    let p = poses();
    let with = |f: fn(&mut ProgramOptions)| {
        let mut o = ProgramOptions::default();
        f(&mut o);
        err(&p, ProgramFormat::Rapid, &o)
    };
    for (e, want) in [
        (with(|o| o.name = "1st".into()), "program name '1st'"),
        (with(|o| o.name = "a-b".into()), "program name 'a-b'"),
        (with(|o| o.name = "a".repeat(25)), "at most 24 characters"),
        (with(|o| o.settle_s = -1.0), "settle time -1"),
        (with(|o| o.settle_s = f64::NAN), "settle time NaN"),
        (with(|o| o.ur_velocity = 0.0), "URScript speed 0"),
        (
            with(|o| o.ur_acceleration = f64::INFINITY),
            "URScript acceleration inf",
        ),
        (with(|o| o.krl_percent = 0.0), "KRL axis speed 0"),
        (with(|o| o.krl_percent = 150.0), "KRL axis speed 150"),
        (
            with(|o| o.rapid_speed = "v123".into()),
            "RAPID speed 'v123'",
        ),
    ] {
        assert!(e.contains(want), "{e} (wanted {want})");
    }
}

#[test]
fn format_names_and_program_names() {
    for f in ProgramFormat::ALL {
        assert_eq!(ProgramFormat::from_name(f.name()).unwrap(), f);
    }
    let e = ProgramFormat::from_name("gcode").unwrap_err().to_string();
    assert!(
        e.contains("'gcode': expected one of csv, urscript, krl, rapid"),
        "{e}"
    );
    let krl = ProgramFormat::Krl;
    assert_eq!(
        program_name(Path::new("out/circle_comp.src"), krl).unwrap(),
        "circle_comp"
    );
    let e = program_name(Path::new("out/circle-comp.src"), krl)
        .unwrap_err()
        .to_string();
    assert!(
        e.starts_with("out/circle-comp.src: a KRL program is called as its file"),
        "{e}"
    );
    let ur = ProgramFormat::Urscript;
    assert_eq!(
        program_name(Path::new("circle-comp.script"), ur).unwrap(),
        "robokrige_plan"
    );
    assert_eq!(
        program_name(Path::new("plan2.script"), ur).unwrap(),
        "plan2"
    );
}

#[test]
fn a_refused_program_writes_nothing() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("plan.src");
    let mut p = poses();
    p[0].q[0] = f64::NAN;
    assert!(write(&path, &p, ProgramFormat::Krl, &ProgramOptions::default()).is_err());
    assert!(!path.exists());
}

/// The compensated commands as a KRL program: the compensator's joints,
/// every move a path point, and the joints' nominal TCP at the commands.
#[test]
fn compensated_commands_write_as_a_program_of_their_joints() {
    let dir = env!("CARGO_MANIFEST_DIR");
    let data =
        robokrige::dataset::read_csv(format!("{dir}/datasets/comau_lhs.csv").as_ref()).unwrap();
    let data = data.select(&(0..60).collect::<Vec<_>>());
    let opts = KrigingOptions::default()
        .optimizer(OptimizerKind::HookeJeeves)
        .max_evals(200)
        .starts(1);
    let model = ErrorModel::fit(&data, Space::Ejs, &opts).unwrap();
    let robot = kinematics::preset("comau-nj220").unwrap();
    let circle = Trajectory::read_csv(format!("{dir}/datasets/comau_circle.csv").as_ref()).unwrap();
    let res = compensate(&robot, &model, &circle, &CompensationOptions::default()).unwrap();

    let out = tempfile::tempdir().unwrap();
    let path = out.path().join("circle_comp.src");
    let target = CommandsOutput::new(&path, Some(ProgramFormat::Krl), &robot).unwrap();
    target.write(&res).unwrap();
    let (name, moves) = parse_krl(&std::fs::read_to_string(&path).unwrap());
    assert_eq!(name, "circle_comp");
    assert_eq!(moves.len(), circle.len());
    for (i, (m, q)) in moves.iter().zip(&res.joints).enumerate() {
        assert_eq!(
            (m.measure, m.label.as_deref(), m.wait_s),
            (None, Some("path"), None)
        );
        for (a, b) in m.q.iter().zip(q) {
            assert!((a - b).abs() < TOL, "move {i}: {a} vs {b}");
        }
        let tcp = robot.position(&m.q).unwrap();
        let cmd = res.commands.poses[i].translation.vector;
        assert!(
            (tcp - cmd).norm() < 1e-3,
            "move {i}: {}",
            (tcp - cmd).norm()
        );
    }
    // refused before any work: a KRL name that is not the file's, a SCARA in URScript
    let bad = out.path().join("circle-comp.src");
    assert!(CommandsOutput::new(&bad, Some(ProgramFormat::Krl), &robot).is_err());
    let scara = kinematics::preset("scara-rh3frh5515").unwrap();
    let e = CommandsOutput::new(&path, Some(ProgramFormat::Urscript), &scara).unwrap_err();
    assert!(e.to_string().contains("movej takes the 6 joints"), "{e}");
    assert!(CommandsOutput::new(&path, Some(ProgramFormat::Csv), &scara).is_ok());
}
