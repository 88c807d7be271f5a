//! The bad-input catalogue, table-driven: every case runs the
//! `robokrige` binary on files written for it and asserts
//!
//! - the exit code (1: a clear error, 2: bad usage, 0: a documented
//!   graceful result);
//! - for an error, one `error:` line, the last one, holding every expected
//!   fragment: the file it concerns, and the line and column where there
//!   is one;
//! - that no input file changed: each input's bytes are hashed before the
//!   run and compared after.
//!
//! All cases run in one test and every failure is listed, by case name.

mod common;

use std::collections::hash_map::DefaultHasher;
use std::hash::{Hash, Hasher};
use std::path::{Path, PathBuf};
use std::process::Command;

/// What a case must give.
enum Expect {
    /// Exit 1; the one error line holds every fragment.
    Fail(Vec<String>),
    /// Exit 2 (clap usage error).
    Usage,
    /// Exit 0; stderr holds every fragment (warnings).
    Ok(Vec<String>),
}

struct Case {
    name: &'static str,
    args: Vec<String>,
    /// Files that must be unchanged afterwards.
    inputs: Vec<PathBuf>,
    env: Vec<(&'static str, &'static str)>,
    expect: Expect,
}

thread_local! {
    /// This test's files, removed when it ends.
    static DIR: common::Scratch = common::Scratch::new("robokrige-catalogue");
    /// This test's good campaign and the model fitted on it.
    static GOOD: (PathBuf, PathBuf) = fit_good();
}

/// The folder of this test's files.
fn dir() -> PathBuf {
    DIR.with(|d| d.path().to_path_buf())
}

fn path(name: &str) -> PathBuf {
    dir().join(name)
}

fn s(p: &Path) -> String {
    p.display().to_string()
}

fn write(name: &str, bytes: impl AsRef<[u8]>) -> PathBuf {
    let p = path(name);
    std::fs::write(&p, bytes).unwrap();
    p
}

fn shipped(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("datasets")
        .join(name)
}

/// A copy of a shipped file in the run's folder (inputs are never the
/// shipped files themselves).
fn copy(name: &str) -> PathBuf {
    let p = path(name);
    std::fs::copy(shipped(name), &p).unwrap();
    p
}

fn hash(p: &Path) -> Option<u64> {
    let bytes = std::fs::read(p).ok()?;
    let mut h = DefaultHasher::new();
    bytes.hash(&mut h);
    Some(h.finish())
}

const HEADER: &str = "q1,q2,q3,q4,q5,q6,ex,ey,ez";

fn row(i: usize) -> String {
    common::synthetic_row(i)
}

/// `rows` rows under `header`, each row edited by `edit(i, row)`.
fn campaign_with(header: &str, rows: usize, edit: impl Fn(usize, String) -> String) -> String {
    let mut s = format!("{header}\n");
    for i in 0..rows {
        s += &edit(i, row(i));
        s.push('\n');
    }
    s
}

fn campaign(rows: usize) -> String {
    campaign_with(HEADER, rows, |_, r| r)
}

/// Replace cell `col` (0-based) of data row `at` (0-based).
fn with_cell(at: usize, col: usize, value: &'static str) -> impl Fn(usize, String) -> String {
    move |i, r| {
        if i != at {
            return r;
        }
        let mut cells: Vec<String> = r.split(',').map(str::to_string).collect();
        cells[col] = value.to_string();
        cells.join(",")
    }
}

/// The good campaign and a model fitted on it.
fn good() -> (PathBuf, PathBuf) {
    GOOD.with(|g| g.clone())
}

fn fit_good() -> (PathBuf, PathBuf) {
    let data = write("good.csv", campaign(24));
    let model = path("good.json");
    let (c, _, err) = common::rk(&["fit", &s(&data), "--optimizer", "hj", "-o", &s(&model)]);
    assert_eq!(c, 0, "{err}");
    (data, model)
}

/// The good model's JSON with `edit` applied, as a new file.
fn tampered(name: &str, edit: impl Fn(&mut serde_json::Value)) -> PathBuf {
    let text = std::fs::read_to_string(&good().1).unwrap();
    let mut v: serde_json::Value = serde_json::from_str(&text).unwrap();
    edit(&mut v);
    write(name, serde_json::to_string(&v).unwrap())
}

fn fail(fragments: &[&str]) -> Expect {
    Expect::Fail(fragments.iter().map(|f| f.to_string()).collect())
}

fn ok(fragments: &[&str]) -> Expect {
    Expect::Ok(fragments.iter().map(|f| f.to_string()).collect())
}

fn case(name: &'static str, args: &[&str], inputs: &[&Path], expect: Expect) -> Case {
    Case {
        name,
        args: args.iter().map(|a| a.to_string()).collect(),
        inputs: inputs.iter().map(|p| p.to_path_buf()).collect(),
        env: Vec::new(),
        expect,
    }
}

/// `fit FILE -o out.json` on the campaign text `text`, expecting `expect`.
fn fit_case(name: &'static str, file: &str, text: impl AsRef<[u8]>, expect: Expect) -> Case {
    let f = write(file, text);
    let out = s(&path(&format!("{file}.model.json")));
    case(
        name,
        &["fit", &s(&f), "--optimizer", "hj", "-o", &out],
        &[&f],
        expect,
    )
}

/// `predict MODEL good.csv -o p.csv` with a model file, expecting `expect`.
fn predict_case(name: &'static str, model: PathBuf, expect: Expect) -> Case {
    let (data, _) = &good();
    let out = s(&path(&format!("{name}.pred.csv")));
    case(
        name,
        &["predict", &s(&model), &s(data), "-o", &out],
        &[&model, data],
        expect,
    )
}

/// `compensate TRAJ --model M -o c.csv` on trajectory text, expecting `expect`.
fn traj_case(name: &'static str, file: &str, text: impl AsRef<[u8]>, expect: Expect) -> Case {
    let t = write(file, text);
    let (_, model) = &good();
    let out = s(&path(&format!("{file}.comp.csv")));
    case(
        name,
        &[
            "compensate",
            &s(&t),
            "--model",
            &s(model),
            "--robot",
            "comau-nj220",
            "-o",
            &out,
        ],
        &[&t, model],
        expect,
    )
}

fn csv_reader_cases() -> Vec<Case> {
    let e = 6; // column index of ex
    vec![
        fit_case(
            "csv_empty_file",
            "empty.csv",
            "",
            fail(&["empty.csv", "empty"]),
        ),
        fit_case(
            "csv_blank_lines_only",
            "blank.csv",
            "\n  \n\n",
            fail(&["blank.csv", "empty"]),
        ),
        fit_case(
            "csv_header_only",
            "header_only.csv",
            format!("{HEADER}\n"),
            fail(&["header_only.csv", "no data rows"]),
        ),
        fit_case(
            "csv_no_q1",
            "no_q.csv",
            "a,b,ex,ey,ez\n1,2,0,0,0\n",
            fail(&["no_q.csv", "no q1 column"]),
        ),
        fit_case(
            "csv_q_gap",
            "q_gap.csv",
            "q1,q3,ex,ey,ez\n1,2,0,0,0\n",
            fail(&["q_gap.csv:1", "q2 is missing"]),
        ),
        fit_case(
            "csv_q0",
            "q0.csv",
            "q0,q1,ex,ey,ez\n1,2,0,0,0\n",
            fail(&["q0.csv:1", "'q0'", "numbered from 1"]),
        ),
        fit_case(
            "csv_leading_zero",
            "q01.csv",
            "q01,ex,ey,ez\n1,0,0,0\n",
            fail(&["q01.csv:1", "'q01'"]),
        ),
        fit_case(
            "csv_duplicate_header",
            "dup.csv",
            "q1,q1,ex,ey,ez\n1,2,0,0,0\n",
            fail(&["dup.csv:1", "appears twice"]),
        ),
        fit_case(
            "csv_empty_header_cell",
            "empty_cell.csv",
            "q1,,ex,ey,ez\n1,2,0,0,0\n",
            fail(&["empty_cell.csv:1", "header cell 2 is empty"]),
        ),
        fit_case(
            "csv_trailing_commas",
            "trailing.csv",
            campaign(24).replace('\n', ",\n"),
            fail(&["trailing.csv:1", "header cell 10 is empty"]),
        ),
        fit_case(
            "csv_ragged_row_short",
            "short.csv",
            campaign_with(HEADER, 24, |i, r| {
                if i == 2 {
                    r.rsplit_once(',').unwrap().0.to_string()
                } else {
                    r
                }
            }),
            fail(&["short.csv:4", "8 cells but the header has 9"]),
        ),
        fit_case(
            "csv_ragged_row_long",
            "long.csv",
            campaign_with(HEADER, 24, |i, r| if i == 5 { r + ",1" } else { r }),
            fail(&["long.csv:7", "10 cells"]),
        ),
        fit_case(
            "csv_text_joint",
            "text_q.csv",
            campaign_with(HEADER, 24, with_cell(3, 1, "abc")),
            fail(&["text_q.csv:5", "'q2'", "expected a number, found 'abc'"]),
        ),
        fit_case(
            "csv_empty_joint",
            "empty_q.csv",
            campaign_with(HEADER, 24, with_cell(0, 0, "")),
            fail(&["empty_q.csv:2", "'q1'", "missing value"]),
        ),
        fit_case(
            "csv_nan_error",
            "nan.csv",
            campaign_with(HEADER, 24, with_cell(7, e, "NaN")),
            fail(&["nan.csv:9", "'ex'", "NaN/inf"]),
        ),
        fit_case(
            "csv_inf_error",
            "inf.csv",
            campaign_with(HEADER, 24, with_cell(7, e + 1, "-inf")),
            fail(&["inf.csv:9", "'ey'", "NaN/inf"]),
        ),
        fit_case(
            "csv_error_1e300",
            "e300.csv",
            campaign_with(HEADER, 24, with_cell(4, e, "1e300")),
            fail(&["e300.csv:6", "'ex'", "cannot be a TCP error in mm"]),
        ),
        fit_case(
            "csv_error_in_micrometres",
            "um.csv",
            campaign_with(HEADER, 24, with_cell(4, e + 2, "2500")),
            fail(&["um.csv:6", "'ez'", "check the units"]),
        ),
        fit_case(
            "csv_joint_1e9",
            "q1e9.csv",
            campaign_with(HEADER, 24, with_cell(10, 2, "1e9")),
            fail(&["q1e9.csv:12", "'q3'", "joint value"]),
        ),
        fit_case(
            "csv_position_1e9",
            "x1e9.csv",
            campaign_with(&format!("{HEADER},x,y,z"), 24, |i, r| {
                if i == 1 {
                    r + ",1e9,0,0"
                } else {
                    r + ",1000,0,500"
                }
            }),
            fail(&["x1e9.csv:3", "'x'", "TCP coordinate"]),
        ),
        fit_case(
            "csv_partial_errors",
            "partial_e.csv",
            "q1,ex,ey\n1,0,0\n",
            fail(&["partial_e.csv:1", "found ex,ey but not ez"]),
        ),
        fit_case(
            "csv_partial_positions",
            "partial_x.csv",
            "q1,x,z,ex,ey,ez\n1,0,0,0,0,0\n",
            fail(&["partial_x.csv:1", "found x,z but not y"]),
        ),
        fit_case(
            "csv_direction_half",
            "dir_half.csv",
            "q1,dir1,ex,ey,ez\n1,0.5,0,0,0\n",
            fail(&["dir_half.csv:2", "'dir1'", "+1 or -1"]),
        ),
        fit_case(
            "csv_direction_partial",
            "dir_part.csv",
            "q1,q2,dir1,ex,ey,ez\n1,2,1,0,0,0\n",
            fail(&["dir_part.csv:1", "missing direction column(s) dir2"]),
        ),
        fit_case(
            "csv_direction_beyond_joints",
            "dir_extra.csv",
            "q1,dir1,dir2,ex,ey,ez\n1,1,1,0,0,0\n",
            fail(&["dir_extra.csv:1", "'dir2'", "no joint column q2"]),
        ),
        fit_case(
            "csv_invalid_utf8",
            "latin1.csv",
            [campaign(3).as_bytes(), b"1,2,3,4,5,6,0,0,0\xe9\n"].concat(),
            fail(&["latin1.csv:5", "UTF-8"]),
        ),
        fit_case(
            "csv_crlf_line_numbers",
            "crlf.csv",
            campaign_with(HEADER, 24, with_cell(4, 0, "x")).replace('\n', "\r\n"),
            fail(&["crlf.csv:6", "'q1'"]),
        ),
        fit_case(
            "csv_cr_only_line_numbers",
            "cr.csv",
            campaign_with(HEADER, 24, with_cell(4, 0, "x")).replace('\n', "\r"),
            fail(&["cr.csv:6", "'q1'"]),
        ),
        fit_case(
            "csv_blank_lines_counted",
            "blanks.csv",
            format!("\n\n{}", campaign_with(HEADER, 24, with_cell(1, 0, "x"))),
            fail(&["blanks.csv:5", "'q1'"]),
        ),
        fit_case(
            "csv_quoted_newline_counted",
            "quoted.csv",
            campaign_with(&format!("{HEADER},note"), 24, |i, r| match i {
                0 => r + ",\"two\nlines\"",
                3 => r.replacen("-", "x", 1) + ",b",
                _ => r + ",a",
            })
            .replacen(",x", ",xx", 1),
            fail(&["quoted.csv:6", "expected a number"]),
        ),
        case(
            "csv_no_errors_for_fit",
            &[
                "fit",
                &s(&write("poses.csv", "q1,q2\n1,2\n3,4\n")),
                "-o",
                &s(&path("poses.json")),
            ],
            &[&path("poses.csv")],
            fail(&["poses.csv", "no ex,ey,ez columns"]),
        ),
        case(
            "csv_missing_file",
            &[
                "fit",
                &s(&path("does_not_exist.csv")),
                "-o",
                &s(&path("x.json")),
            ],
            &[],
            fail(&["does_not_exist.csv", "No such file"]),
        ),
        case(
            "csv_is_a_folder",
            &["fit", &s(&dir()), "-o", &s(&path("folder.json"))],
            &[],
            fail(&[&s(&dir())]),
        ),
        fit_case(
            "csv_bom_accepted",
            "bom.csv",
            [b"\xEF\xBB\xBF".as_slice(), campaign(24).as_bytes()].concat(),
            ok(&[]),
        ),
        fit_case(
            "csv_trailing_whitespace_line_accepted",
            "ws_tail.csv",
            campaign(24) + "   \n",
            ok(&[]),
        ),
        fit_case(
            "csv_padded_cells_accepted",
            "padded.csv",
            campaign(24).replace(',', " , "),
            ok(&[]),
        ),
        fit_case(
            "csv_radians_warned",
            "radians.csv",
            campaign_with(HEADER, 24, |_, r| {
                let mut c: Vec<String> = r.split(',').map(str::to_string).collect();
                for v in c.iter_mut().take(6) {
                    *v = format!("{:.4}", v.parse::<f64>().unwrap() / 57.3);
                }
                c.join(",")
            }),
            ok(&["radians.csv", "radians"]),
        ),
        fit_case(
            "csv_minus_zero_is_a_repeat",
            "minus_zero.csv",
            "q1,q2,dir1,dir2,ex,ey,ez\n0.0,1,1,1,0.1,0.2,0.3\n-0.0,1,1,1,0.1,0.2,0.3\n\
             5,6,1,1,0.2,0.1,0\n7,8,1,1,0.3,0,0.1\n9,1,1,1,0,0.1,0.2\n",
            ok(&["minus_zero.csv", "1 pose(s) repeat an earlier pose"]),
        ),
    ]
}

fn covariate_cases() -> Vec<Case> {
    let h = format!("{HEADER},temp_c,operator");
    let cov = |bad: Option<(usize, &'static str)>| {
        campaign_with(&h, 24, move |i, r| {
            let t = match bad {
                Some((at, v)) if at == i => v.to_string(),
                _ => format!("{:.2}", 20.0 + 0.1 * i as f64),
            };
            format!("{r},{t},anna")
        })
    };
    vec![
        fit_case(
            "covariate_inf_is_named",
            "cov_inf.csv",
            cov(Some((6, "inf"))),
            ok(&["cov_inf.csv", "'temp_c'", "line 8", "'inf'"]),
        ),
        fit_case(
            "covariate_text_cell_is_named",
            "cov_text.csv",
            cov(Some((2, "warm"))),
            ok(&["cov_text.csv", "'temp_c'", "line 4", "'warm'"]),
        ),
        fit_case(
            "covariate_huge_is_named",
            "cov_huge.csv",
            cov(Some((3, "1e300"))),
            ok(&["cov_huge.csv", "'temp_c'", "line 5"]),
        ),
        fit_case(
            "covariate_missing_cells_are_fine",
            "cov_gap.csv",
            cov(Some((3, ""))),
            ok(&[]),
        ),
    ]
}

fn output_cases() -> Vec<Case> {
    let (data, model) = &good();
    let d = s(data);
    let m = s(model);
    let link = path("hardlink.csv");
    let _ = std::fs::remove_file(&link);
    std::fs::hard_link(data, &link).unwrap();
    let sym = path("symlink.csv");
    let _ = std::fs::remove_file(&sym);
    #[cfg(unix)]
    std::os::unix::fs::symlink(data, &sym).unwrap();
    let ro = write("readonly.json", "keep me");
    let mut perm = std::fs::metadata(&ro).unwrap().permissions();
    perm.set_readonly(true);
    std::fs::set_permissions(&ro, perm).unwrap();
    let traj = copy("comau_circle.csv");
    let truth = copy("comau_circle.truth.json");
    let dotted = format!("{}/./good.csv", dir().display());
    let same = "is the input";
    vec![
        case(
            "out_fit_onto_data",
            &["fit", &d, "-o", &d],
            &[data],
            fail(&[same]),
        ),
        case(
            "out_fit_onto_data_other_spelling",
            &["fit", &d, "-o", &dotted],
            &[data],
            fail(&[same]),
        ),
        case(
            "out_fit_onto_hard_link",
            &["fit", &d, "-o", &s(&link)],
            &[data],
            fail(&[same]),
        ),
        case(
            "out_fit_onto_symlink",
            &["fit", &d, "-o", &s(&sym)],
            &[data],
            fail(&[same]),
        ),
        case(
            "out_predict_onto_model",
            &["predict", &m, &d, "-o", &m],
            &[data, model],
            fail(&[same]),
        ),
        case(
            "out_predict_onto_poses",
            &["predict", &m, &d, "-o", &d],
            &[data, model],
            fail(&[same]),
        ),
        case(
            "out_predict_two_outputs_one_file",
            &[
                "predict",
                &m,
                &d,
                "-o",
                &s(&path("both.out")),
                "--json",
                &s(&path("both.out")),
            ],
            &[data, model],
            fail(&["are the same file"]),
        ),
        case(
            "out_compensate_onto_trajectory",
            &[
                "compensate",
                &s(&traj),
                "--model",
                &m,
                "--robot",
                "comau-nj220",
                "-o",
                &s(&traj),
            ],
            &[&traj, model],
            fail(&[same]),
        ),
        case(
            "out_register_onto_data",
            &[
                "physics",
                "register",
                &d,
                "--robot",
                "comau-nj220",
                "-o",
                &d,
            ],
            &[data],
            fail(&[same]),
        ),
        case(
            "out_cv_json_onto_data",
            &["cv", &d, "--json", &d],
            &[data],
            fail(&[same]),
        ),
        case(
            "out_diagnose_report_onto_data",
            &["diagnose", &d, "--report", &d],
            &[data],
            fail(&[same]),
        ),
        case(
            "out_diagnose_model_onto_data",
            &["diagnose", &d, "--model-out", &d],
            &[data],
            fail(&[same]),
        ),
        case(
            "out_holdout_json_onto_data",
            &["holdout", &d, "--robot", "comau-nj220", "--json", &d],
            &[data],
            fail(&[same]),
        ),
        case(
            "out_evaluate_json_onto_trajectory",
            &[
                "evaluate",
                &s(&traj),
                &s(&traj),
                "--truth",
                &s(&truth),
                "--json",
                &s(&truth),
            ],
            &[&traj, &truth],
            fail(&[same]),
        ),
        case(
            "out_simulate_truth_onto_output",
            &[
                "simulate",
                "--poses",
                "5",
                "-o",
                &s(&path("sim.csv")),
                "--truth",
                &s(&path("sim.csv")),
            ],
            &[],
            fail(&["are the same file"]),
        ),
        case(
            "out_identify_two_outputs_one_file",
            &[
                "physics",
                "identify",
                &s(&copy("scara_indexing.csv")),
                "-o",
                &s(&path("phys.json")),
                "--dh-output",
                &s(&path("phys.json")),
            ],
            &[&path("scara_indexing.csv")],
            fail(&["are the same file"]),
        ),
        case(
            "out_missing_folder",
            &["fit", &d, "-o", &s(&path("no/such/folder/m.json"))],
            &[data],
            fail(&["m.json", "does not exist"]),
        ),
        case(
            "out_is_a_folder",
            &["fit", &d, "-o", &s(&dir())],
            &[data],
            fail(&["is a folder"]),
        ),
        case(
            "out_read_only_file",
            &["fit", &d, "-o", &s(&ro)],
            &[data, &ro],
            fail(&["readonly.json", "read-only"]),
        ),
        case(
            "out_predict_read_only_json",
            &[
                "predict",
                &m,
                &d,
                "-o",
                &s(&path("p_ro.csv")),
                "--json",
                &s(&ro),
            ],
            &[data, model, &ro],
            fail(&["readonly.json", "read-only"]),
        ),
    ]
}

fn model_cases() -> Vec<Case> {
    use serde_json::json;
    let o0 = |v: &mut serde_json::Value| v["outputs"][0].take();
    let _ = o0;
    vec![
        predict_case(
            "model_not_json",
            write("garbage.json", "{ not json"),
            fail(&["garbage.json"]),
        ),
        predict_case(
            "model_empty_file",
            write("empty.json", ""),
            fail(&["empty.json"]),
        ),
        predict_case(
            "model_other_format",
            write("other.json", r#"{"format":"something","version":1}"#),
            fail(&["other.json", "not a robokrige error model"]),
        ),
        predict_case(
            "model_future_version",
            tampered("v99.json", |v| v["version"] = json!(99)),
            fail(&["v99.json", "version"]),
        ),
        predict_case(
            "model_truncated",
            {
                let text = std::fs::read_to_string(&good().1).unwrap();
                write("truncated.json", &text[..text.len() / 2])
            },
            fail(&["truncated.json"]),
        ),
        predict_case(
            "model_negative_theta",
            tampered("theta.json", |v| v["outputs"][0]["theta"][0] = json!(-1.0)),
            fail(&["theta.json", "ξ is negative"]),
        ),
        predict_case(
            "model_zero_input_std",
            tampered("std0.json", |v| v["inputs"]["norm"]["std"][0] = json!(0.0)),
            fail(&["std0.json", "inputs.norm", "std[0]"]),
        ),
        predict_case(
            "model_huge_input_mean",
            tampered("mean.json", |v| {
                v["inputs"]["norm"]["mean"][2] = json!(1e300)
            }),
            fail(&["mean.json", "mean[2]"]),
        ),
        predict_case(
            "model_y_std_1e308",
            tampered("ystd.json", |v| v["outputs"][1]["y_std"] = json!(1e308)),
            fail(&["ystd.json", "y_std"]),
        ),
        predict_case(
            "model_y_std_1e10",
            tampered("ystd10.json", |v| v["outputs"][1]["y_std"] = json!(1e10)),
            fail(&["ystd10.json", "output ey", "y_std"]),
        ),
        predict_case(
            "model_y_std_negative",
            tampered("ystdneg.json", |v| v["outputs"][2]["y_std"] = json!(-1.0)),
            fail(&["ystdneg.json"]),
        ),
        predict_case(
            "model_y_mean_1e10",
            tampered("ymean.json", |v| v["outputs"][0]["y_mean"] = json!(1e10)),
            fail(&["ymean.json", "y_mean"]),
        ),
        predict_case(
            "model_negative_sigma2",
            tampered("s2neg.json", |v| v["outputs"][0]["sigma2"] = json!(-1.0)),
            fail(&["s2neg.json", "σ²"]),
        ),
        predict_case(
            "model_zero_sigma2",
            tampered("s2zero.json", |v| v["outputs"][0]["sigma2"] = json!(0.0)),
            fail(&["s2zero.json", "σ² is 0"]),
        ),
        predict_case(
            "model_negative_nugget",
            tampered("nugget.json", |v| v["outputs"][0]["nugget"] = json!(-0.1)),
            fail(&["nugget.json", "nugget"]),
        ),
        predict_case(
            "model_null_beta",
            tampered("beta.json", |v| v["outputs"][0]["beta"][0] = json!(null)),
            fail(&["beta.json"]),
        ),
        predict_case(
            "model_short_gamma",
            tampered("gamma.json", |v| {
                v["outputs"][0]["gamma"].as_array_mut().unwrap().pop();
            }),
            fail(&["gamma.json", "disagree"]),
        ),
        predict_case(
            "model_two_outputs",
            tampered("two.json", |v| {
                v["outputs"].as_array_mut().unwrap().pop();
            }),
            fail(&["two.json", "inconsistent"]),
        ),
        predict_case(
            "model_inverted_joint_range",
            tampered("range.json", |v| v["joint_range"][0] = json!([5.0, -5.0])),
            fail(&["range.json", "joint_range[0]"]),
        ),
        predict_case(
            "model_short_joint_range",
            tampered("range_len.json", |v| {
                v["joint_range"].as_array_mut().unwrap().pop();
            }),
            fail(&["range_len.json", "joint_range"]),
        ),
        predict_case(
            "model_huge_training_input",
            tampered("xt.json", |v| {
                v["outputs"][0]["x_train"][0][0] = json!(1e200)
            }),
            fail(&["xt.json", "training input"]),
        ),
        predict_case(
            "model_periodic_joint_out_of_range",
            tampered("periodic.json", |v| v["inputs"]["periodic"] = json!([9])),
            fail(&["periodic.json", "inconsistent", "periodic joint 10"]),
        ),
        predict_case(
            "model_zero_joints",
            tampered("nj.json", |v| v["inputs"]["n_joints"] = json!(0)),
            fail(&["nj.json"]),
        ),
        predict_case(
            "model_fused_trend_with_zero_scale",
            {
                // found by the model_loader fuzz target (fuzz/seeds)
                let p = path("fused_std0.json");
                std::fs::copy(
                    Path::new(env!("CARGO_MANIFEST_DIR"))
                        .join("fuzz/seeds/model_loader/crash-fused-std0.json"),
                    &p,
                )
                .unwrap();
                p
            },
            fail(&["fused_std0.json", "trend is not finite"]),
        ),
        predict_case(
            "model_kinematic_trend_with_short_scales",
            {
                // found by the model_loader fuzz target (fuzz/seeds): the
                // load-time evaluation of an unvalidated kinematic trend
                // indexed out of bounds
                let p = path("kin_scales.json");
                std::fs::copy(
                    Path::new(env!("CARGO_MANIFEST_DIR"))
                        .join("fuzz/seeds/model_loader/crash-kinematic-scales.json"),
                    &p,
                )
                .unwrap();
                p
            },
            fail(&["kin_scales.json", "kinematic trend"]),
        ),
        predict_case(
            "model_bad_options",
            tampered("opts.json", |v| v["options"]["starts"] = json!(0)),
            fail(&["opts.json", "options"]),
        ),
    ]
}

fn predict_cases() -> Vec<Case> {
    let (_, model) = &good();
    let m = s(model);
    let four = write("four.csv", "q1,q2,q3,q4\n1,2,3,4\n");
    vec![
        case(
            "predict_wrong_joint_count",
            &["predict", &m, &s(&four), "-o", &s(&path("p4.csv"))],
            &[model, &four],
            fail(&["four.csv", "has 4 joints but the model was fitted on 6"]),
        ),
        case(
            "predict_missing_poses_file",
            &[
                "predict",
                &m,
                &s(&path("nope.csv")),
                "-o",
                &s(&path("p.csv")),
            ],
            &[model],
            fail(&["nope.csv"]),
        ),
        case(
            "predict_bad_pose_cell",
            &[
                "predict",
                &m,
                &s(&write(
                    "bad_pose.csv",
                    campaign_with(HEADER, 5, with_cell(2, 3, "?")),
                )),
                "-o",
                &s(&path("p.csv")),
            ],
            &[model, &path("bad_pose.csv")],
            fail(&["bad_pose.csv:4", "'q4'"]),
        ),
    ]
}

fn trajectory_cases() -> Vec<Case> {
    let good_traj = "x,y,z\n1500,0,1200\n1500,10,1200\n1500,20,1200\n1500,30,1200\n1500,40,1200\n";
    let bad6 = "x,y,z\n1500,0,1200\n1500,10,1200\n1500,20,1200\n1500,30,1200\n1500,?,1200\n";
    vec![
        traj_case(
            "traj_crlf_line",
            "t_crlf.csv",
            bad6.replace('\n', "\r\n"),
            fail(&["t_crlf.csv:6", "'y'"]),
        ),
        traj_case(
            "traj_cr_only_line",
            "t_cr.csv",
            bad6.replace('\n', "\r"),
            fail(&["t_cr.csv:6", "'y'"]),
        ),
        traj_case(
            "traj_blank_lines_counted",
            "t_blank.csv",
            bad6.replacen("\n", "\n\n", 2),
            fail(&["t_blank.csv:8", "'y'"]),
        ),
        traj_case(
            "traj_trailing_commas",
            "t_commas.csv",
            good_traj.replace('\n', ",\n"),
            fail(&["t_commas.csv:1", "header cell 4 is empty"]),
        ),
        traj_case(
            "traj_ragged",
            "t_ragged.csv",
            "x,y,z\n1500,0,1200\n1500,0\n",
            fail(&["t_ragged.csv:3", "2 cells"]),
        ),
        traj_case(
            "traj_roll_only",
            "t_roll.csv",
            "x,y,z,roll_deg\n1500,0,1200,0\n",
            fail(&["t_roll.csv:1", "found roll_deg but not pitch_deg,yaw_deg"]),
        ),
        traj_case(
            "traj_roll_yaw_only",
            "t_ry.csv",
            "x,y,z,roll_deg,yaw_deg\n1500,0,1200,0,0\n",
            fail(&["t_ry.csv:1", "not pitch_deg"]),
        ),
        traj_case(
            "traj_no_z",
            "t_noz.csv",
            "x,y\n1,2\n",
            fail(&["t_noz.csv:1", "x, y, z"]),
        ),
        traj_case(
            "traj_empty",
            "t_empty.csv",
            "",
            fail(&["t_empty.csv", "empty"]),
        ),
        traj_case(
            "traj_header_only",
            "t_header.csv",
            "x,y,z\n",
            fail(&["t_header.csv", "no points"]),
        ),
        traj_case(
            "traj_nan",
            "t_nan.csv",
            "x,y,z\n1500,0,NaN\n",
            fail(&["t_nan.csv:2", "'z'", "NaN/inf"]),
        ),
        traj_case(
            "traj_huge_coordinate",
            "t_huge.csv",
            "x,y,z\n1e9,0,1200\n",
            fail(&["t_huge.csv:2", "'x'", "TCP coordinate"]),
        ),
        traj_case(
            "traj_duplicate_column",
            "t_dup.csv",
            "x,y,z,z\n1,2,3,4\n",
            fail(&["t_dup.csv:1", "'z'", "appears twice"]),
        ),
        traj_case(
            "traj_invalid_utf8",
            "t_utf8.csv",
            b"x,y,z\n1500,0,1200\n1500,0,\xff\n",
            fail(&["t_utf8.csv:3", "UTF-8"]),
        ),
        traj_case(
            "traj_bad_angle",
            "t_angle.csv",
            "x,y,z,roll_deg,pitch_deg,yaw_deg\n1500,0,1200,0,abc,0\n",
            fail(&["t_angle.csv:2", "'pitch_deg'"]),
        ),
        traj_case(
            "traj_pose_list_for_another_robot",
            "t_q4.csv",
            "q1,q2,q3,q4\n1,2,3,4\n",
            fail(&["t_q4.csv", "robot 'comau-nj220' has 6 joints"]),
        ),
        traj_case(
            "traj_pose_list_bad_cell",
            "t_qbad.csv",
            "q1,q2,q3,q4,q5,q6\n1,2,3,4,5,6\n1,2,x,4,5,6\n",
            fail(&["t_qbad.csv:3", "'q3'"]),
        ),
    ]
}

fn command_cases() -> Vec<Case> {
    let (data, model) = &good();
    let d = s(data);
    let m = s(model);
    let traj = copy("comau_circle.csv");
    let truth = copy("comau_circle.truth.json");
    let scara = copy("scara_indexing.csv");
    let poses = write("pose_list.csv", "q1,q2,q3,q4,q5,q6\n1,2,3,4,5,6\n");
    let not_truth = write("not_truth.json", "{\"a\": 1}");
    let out = |n: &str| s(&path(n));
    vec![
        // the kinematic trend has no separate calibration to set
        case(
            "fit_kinematic_with_a_calibration_option",
            &[
                "fit",
                &d,
                "--robot",
                "comau-nj220",
                "--kinematic",
                "--geometric",
                "-o",
                &out("k.json"),
            ],
            &[data],
            Expect::Usage,
        ),
        // a tracker position alone would leave out no pose
        case(
            "plan_tracker_without_a_limit",
            &[
                "plan",
                "--robot",
                "comau-nj220",
                "--budget",
                "5",
                "--tracker=0,0,1000",
                "-o",
                &out("p.csv"),
            ],
            &[],
            fail(&["--tracker alone", "--max-range"]),
        ),
        case(
            "plan_region_outside_the_joint_limits",
            &[
                "plan",
                "--robot",
                "comau-nj220",
                "--budget",
                "5",
                "--region",
                &s(&write(
                    "region_oob.csv",
                    "q1,q2,q3,q4,q5,q6\n0,0,-90,0,0,0\n0,120,-90,0,0,0\n",
                )),
                "-o",
                &out("p.csv"),
            ],
            &[],
            fail(&["region_oob.csv", "1 of its 2 poses", "data row 2"]),
        ),
        case(
            "cv_groups_on_a_joint_column",
            &["cv", &d, "--groups", "q1"],
            &[data],
            fail(&["'q1' is a measurement column", "extra columns"]),
        ),
        case(
            "fit_output_dash_is_not_a_file",
            &["fit", &d, "-o", "-"],
            &[data],
            fail(&["-o/--output -: '-' would be a file named '-'", "--json -"]),
        ),
        case(
            "fit_output_dash_attached_is_not_a_file",
            &["fit", &d, "-o-"],
            &[data],
            fail(&["-o/--output -: '-' would be a file named '-'"]),
        ),
        case(
            "cv_groups_dash_is_not_a_column",
            &["cv", &d, "--groups", "-"],
            &[data],
            fail(&[
                "--groups -: '-' is standard output, which only --json takes; give --groups its value",
            ]),
        ),
        case(
            "plan_region_dash_is_not_a_file",
            &[
                "plan",
                "--robot",
                "ur10",
                "--budget",
                "5",
                "--region=-",
                "-o",
                &out("p.csv"),
            ],
            &[],
            fail(&[
                "--region -: '-' would be a file named '-'",
                "no input is read from it",
            ]),
        ),
        case(
            "compensate_plot_dash_is_not_a_file",
            &[
                "compensate",
                "--model",
                &m,
                "--robot",
                "comau-nj220",
                &s(&traj),
                "-o",
                &out("c.csv"),
                "--truth",
                &s(&truth),
                "--plot",
                "-",
            ],
            &[model],
            fail(&[
                "--plot -: '-' would be a file named '-'",
                "give --plot a path",
            ]),
        ),
        case(
            "plan_negative_target",
            &[
                "plan",
                "--robot",
                "comau-nj220",
                "--budget",
                "5",
                "--target-mm=-1",
                "-o",
                &out("p.csv"),
            ],
            &[],
            fail(&["--target-mm", "positive"]),
        ),
        // a calibration option needs a robot to calibrate
        case(
            "fit_geometric_without_robot",
            &["fit", &d, "--geometric", "-o", &out("g.json")],
            &[data],
            Expect::Usage,
        ),
        case(
            "cv_calibration_noise_without_robot",
            &["cv", &d, "--calibration-noise", "0.1"],
            &[data],
            Expect::Usage,
        ),
        // compensate
        case(
            "compensate_unknown_robot",
            &[
                "compensate",
                &s(&traj),
                "--model",
                &m,
                "--robot",
                "r2d2",
                "-o",
                &out("c.csv"),
            ],
            &[&traj, model],
            fail(&["unknown robot 'r2d2'"]),
        ),
        case(
            "compensate_missing_model",
            &[
                "compensate",
                &s(&traj),
                "--model",
                &out("nomodel.json"),
                "--robot",
                "comau-nj220",
                "-o",
                &out("c.csv"),
            ],
            &[&traj],
            fail(&["nomodel.json"]),
        ),
        case(
            "compensate_missing_trajectory",
            &[
                "compensate",
                &out("notraj.csv"),
                "--model",
                &m,
                "--robot",
                "comau-nj220",
                "-o",
                &out("c.csv"),
            ],
            &[model],
            fail(&["notraj.csv"]),
        ),
        // evaluate
        case(
            "evaluate_truth_not_a_truth",
            &["evaluate", &s(&traj), &s(&traj), "--truth", &s(&not_truth)],
            &[&traj, &not_truth],
            fail(&["not_truth.json", "not a simulator truth file"]),
        ),
        case(
            "evaluate_missing_compensated",
            &[
                "evaluate",
                &s(&traj),
                &out("nocomp.csv"),
                "--truth",
                &s(&truth),
            ],
            &[&traj, &truth],
            fail(&["nocomp.csv"]),
        ),
        case(
            "evaluate_wrong_robot",
            &[
                "evaluate",
                &s(&traj),
                &s(&traj),
                "--truth",
                &s(&truth),
                "--robot",
                "ur10",
            ],
            &[&traj, &truth],
            fail(&["ur10"]),
        ),
        // cv
        case(
            "cv_one_fold",
            &["cv", &d, "--folds", "1"],
            &[data],
            fail(&["2 ≤ K ≤ rows"]),
        ),
        case(
            "cv_more_folds_than_rows",
            &["cv", &d, "--folds", "500"],
            &[data],
            fail(&["2 ≤ K ≤ rows"]),
        ),
        case(
            "cv_unknown_method",
            &["cv", &d, "--methods", "magic"],
            &[data],
            fail(&["magic"]),
        ),
        case(
            "cv_no_errors",
            &["cv", &s(&poses)],
            &[&poses],
            fail(&["pose_list.csv", "no ex,ey,ez"]),
        ),
        // diagnose
        case(
            "diagnose_unknown_method",
            &["diagnose", &d, "--method", "magic"],
            &[data],
            fail(&["magic"]),
        ),
        case(
            "diagnose_no_errors",
            &["diagnose", &s(&poses)],
            &[&poses],
            fail(&["pose_list.csv", "no ex,ey,ez"]),
        ),
        case(
            "diagnose_missing_file",
            &["diagnose", &out("gone.csv")],
            &[],
            fail(&["gone.csv"]),
        ),
        // holdout
        case(
            "holdout_too_few_train_rows",
            &["holdout", &d, "--robot", "comau-nj220", "--train", "5"],
            &[data],
            fail(&["--train 5"]),
        ),
        case(
            "holdout_each_fold_without_folds",
            &["holdout", &d, "--robot", "comau-nj220", "--each-fold"],
            &[data],
            fail(&["--each-fold", "--cv K or --groups COLUMN"]),
        ),
        case(
            "holdout_unknown_robot",
            &["holdout", &d, "--robot", "r2d2"],
            &[data],
            fail(&["unknown robot 'r2d2'"]),
        ),
        case(
            "holdout_bad_tool",
            &["holdout", &d, "--robot", "comau-nj220", "--tool", "a,b"],
            &[data],
            fail(&["--tool 'a,b'"]),
        ),
        case(
            "holdout_robot_with_other_joint_count",
            &["holdout", &d, "--robot", "scara-rh3frh5515"],
            &[data],
            fail(&["good.csv", "robot 'scara-rh3frh5515' has 4 joints"]),
        ),
        case(
            "holdout_unknown_optimizer",
            &[
                "holdout",
                &d,
                "--robot",
                "comau-nj220",
                "--train",
                "12",
                "--test",
                "6",
                "--optimizer",
                "magic",
            ],
            &[data],
            // clap's value enum, as for `fit --optimizer`
            Expect::Usage,
        ),
        // fit options
        case(
            "fit_kinematic_robot_with_other_joint_count",
            &[
                "fit",
                &d,
                "--kinematic",
                "--robot",
                "scara-rh3frh5515",
                "-o",
                &out("k.json"),
            ],
            &[data],
            fail(&["good.csv", "robot 'scara-rh3frh5515' has 4 joints"]),
        ),
        case(
            "fit_unknown_method",
            &["fit", &d, "--method", "magic", "-o", &out("k.json")],
            &[data],
            fail(&["magic"]),
        ),
        // physics
        case(
            "physics_identify_six_axis_on_default_robot",
            &["physics", "identify", &d, "-o", &out("ph.json")],
            &[data],
            fail(&["good.csv", "the default robot is scara-rh3frh5515"]),
        ),
        case(
            "physics_identify_six_axis_without_train",
            &[
                "physics",
                "identify",
                &d,
                "--robot",
                "comau-nj220",
                "-o",
                &out("ph.json"),
            ],
            &[data],
            fail(&["--train"]),
        ),
        case(
            "physics_crosstalk_model_not_physics",
            &["physics", "crosstalk", &s(&scara), "--model", &m],
            &[&scara, model],
            fail(&["good.json"]),
        ),
        case(
            "physics_register_without_positions",
            &[
                "physics",
                "register",
                &d,
                "--robot",
                "comau-nj220",
                "-o",
                &out("reg.csv"),
            ],
            &[data],
            fail(&["good.csv"]),
        ),
        case(
            "physics_register_other_joint_count",
            &[
                "physics",
                "register",
                &s(&scara),
                "--robot",
                "comau-nj220",
                "-o",
                &out("reg.csv"),
            ],
            &[&scara],
            fail(&["scara_indexing.csv", "robot 'comau-nj220' has 6 joints"]),
        ),
        case(
            "physics_compare_unknown_robot",
            &["physics", "compare", "--robot", "r2d2"],
            &[],
            fail(&["unknown robot 'r2d2'"]),
        ),
        // simulate
        case(
            "simulate_unknown_robot",
            &["simulate", "--robot", "r2d2", "-o", &out("sim1.csv")],
            &[],
            fail(&["unknown robot 'r2d2'"]),
        ),
        case(
            "simulate_unknown_effect",
            &["simulate", "--effect", "gremlins", "-o", &out("sim2.csv")],
            &[],
            fail(&["gremlins"]),
        ),
        case(
            "simulate_bad_ranges",
            &["simulate", "--ranges", "1,2,3", "-o", &out("sim3.csv")],
            &[],
            fail(&["--ranges"]),
        ),
        // usage
        case("usage_no_subcommand", &[], &[], Expect::Usage),
        case(
            "usage_fit_without_output",
            &["fit", &d],
            &[data],
            Expect::Usage,
        ),
        case(
            "usage_unknown_flag",
            &["fit", &d, "-o", &out("u.json"), "--frobnicate"],
            &[data],
            Expect::Usage,
        ),
        case(
            "usage_folds_not_a_number",
            &["cv", &d, "--folds", "ten"],
            &[data],
            Expect::Usage,
        ),
        case(
            "usage_unknown_subcommand",
            &["calibrate", &d],
            &[data],
            Expect::Usage,
        ),
    ]
}

fn memory_cases() -> Vec<Case> {
    let (data, _) = &good();
    let d = s(data);
    let mut cases = vec![
        case(
            "memory_fit_over_limit",
            &["fit", &d, "-o", &s(&path("mem.json"))],
            &[data],
            fail(&[
                "needs about",
                "ROBOKRIGE_MEMORY_LIMIT",
                "fit at most",
                "head -n",
            ]),
        ),
        case(
            "memory_cv_over_limit",
            &["cv", &d],
            &[data],
            fail(&["needs about", "fit at most"]),
        ),
        case(
            "memory_diagnose_over_limit",
            &["diagnose", &d],
            &[data],
            // 1 kB: no campaign fits, so no row count is offered
            fail(&[
                "a diagnosis of",
                "needs about",
                "not even",
                "raise ROBOKRIGE_MEMORY_LIMIT",
            ]),
        ),
    ];
    for c in &mut cases {
        c.env.push(("ROBOKRIGE_MEMORY_LIMIT", "1K"));
    }
    // 30 MB: a few dozen of the shipped campaign's 300 rows fit
    let lhs = shipped("comau_lhs.csv");
    let mut fewer = case(
        "memory_diagnose_names_the_rows_that_fit",
        &["diagnose", &s(&lhs)],
        &[&lhs],
        fail(&["a diagnosis of 300 rows", "diagnose at most", "`--rows "]),
    );
    fewer.env.push(("ROBOKRIGE_MEMORY_LIMIT", "30M"));
    cases.push(fewer);
    cases
}

/// Run one case; `Err` says what went wrong.
fn run(c: &Case) -> Result<(), String> {
    let before: Vec<Option<u64>> = c.inputs.iter().map(|p| hash(p)).collect();
    // ROBOKRIGE_CATALOGUE_BIN runs the catalogue against another build
    // (e.g. one from before a fix, to see the cases fail there)
    let bin = std::env::var("ROBOKRIGE_CATALOGUE_BIN")
        .unwrap_or_else(|_| env!("CARGO_BIN_EXE_robokrige").to_string());
    let out = Command::new(bin)
        .args(&c.args)
        .envs(c.env.iter().copied())
        .output()
        .map_err(|e| e.to_string())?;
    let code = out.status.code().unwrap_or(-1);
    let err = String::from_utf8_lossy(&out.stderr).to_string();
    for (p, h) in c.inputs.iter().zip(&before) {
        if hash(p) != *h {
            return Err(format!("input {} changed", p.display()));
        }
    }
    match &c.expect {
        Expect::Usage => (code == 2)
            .then_some(())
            .ok_or(format!("exit {code}, expected 2: {err}")),
        Expect::Ok(fragments) => {
            if code != 0 {
                return Err(format!("exit {code}, expected 0: {err}"));
            }
            match fragments.iter().find(|f| !err.contains(f.as_str())) {
                Some(f) => Err(format!("'{f}' not in stderr: {err}")),
                None => Ok(()),
            }
        }
        Expect::Fail(fragments) => {
            if code != 1 {
                return Err(format!("exit {code}, expected 1: {err}"));
            }
            let errors: Vec<&str> = err.lines().filter(|l| l.starts_with("error: ")).collect();
            let last = err.trim_end().lines().last().unwrap_or("");
            if errors.len() != 1 || !last.starts_with("error: ") {
                return Err(format!("not one final error line: {err}"));
            }
            match fragments.iter().find(|f| !last.contains(f.as_str())) {
                Some(f) => Err(format!("'{f}' not in: {last}")),
                None => Ok(()),
            }
        }
    }
}

#[test]
fn catalogue() {
    let groups = [
        csv_reader_cases(),
        covariate_cases(),
        output_cases(),
        model_cases(),
        predict_cases(),
        trajectory_cases(),
        command_cases(),
        memory_cases(),
    ];
    let cases: Vec<Case> = groups.into_iter().flatten().collect();
    assert!(cases.len() >= 100, "{} cases", cases.len());
    let mut names: Vec<&str> = cases.iter().map(|c| c.name).collect();
    names.sort_unstable();
    names.dedup();
    assert_eq!(names.len(), cases.len(), "case names are unique");
    let failures: Vec<String> = cases
        .iter()
        .filter_map(|c| run(c).err().map(|e| format!("{}: {e}", c.name)))
        .collect();
    assert!(
        failures.is_empty(),
        "{} of {} cases failed:\n{}",
        failures.len(),
        cases.len(),
        failures.join("\n")
    );
}

/// An `id` with a comma (or a quote) is quoted in `predict`'s
/// CSV, which reads back with the same ids.
#[test]
fn predicted_ids_are_quoted_and_read_back() {
    let (_, model) = &good();
    let poses = write(
        "ids.csv",
        "id,q1,q2,q3,q4,q5,q6\n\"a,b\",1,2,3,4,5,6\n\"say \"\"hi\"\"\",2,3,4,5,6,7\n",
    );
    let out = path("ids_pred.csv");
    let (c, _, err) = common::rk(&["predict", &s(model), &s(&poses), "-o", &s(&out)]);
    assert_eq!(c, 0, "{err}");
    let back = robokrige::dataset::read_csv(&out).unwrap();
    assert_eq!(
        back.ids.unwrap(),
        vec!["a,b".to_string(), "say \"hi\"".to_string()]
    );
}

/// Every model writer's file loads back (fit, diagnose
/// --model-out); the loader is the same one `predict` uses.
#[test]
fn written_models_load_back() {
    let (data, model) = &good();
    robokrige::model::ErrorModel::load(model).unwrap();
    let after = path("diag_model.json");
    let (c, _, err) = common::rk(&[
        "diagnose",
        &s(data),
        "--method",
        "js-hj",
        "--max-effects",
        "1",
        "--permutations",
        "19",
        "--model-out",
        &s(&after),
    ]);
    assert_eq!(c, 0, "{err}");
    robokrige::model::ErrorModel::load(&after).unwrap();
}
