//! Reading, validating and writing the measurement CSV.

use std::path::{Path, PathBuf};

use robokrige::Error;
use robokrige::dataset::*;

fn read(s: &str) -> robokrige::Result<Dataset> {
    read_csv_from(s.as_bytes(), "test.csv")
}

/// Assert a `Error::Csv` at `line` / `column` whose message contains `needle`.
#[track_caller]
fn assert_csv_err(s: &str, line: u64, column: Option<&str>, needle: &str) {
    match read(s) {
        Err(Error::Csv {
            file,
            line: l,
            column: c,
            message,
        }) => {
            assert_eq!(file, "test.csv");
            assert_eq!(l, line, "line; message: {message}");
            assert_eq!(c.as_deref(), column, "column; message: {message}");
            assert!(message.contains(needle), "'{message}' lacks '{needle}'");
        }
        other => panic!("expected Error::Csv, got {other:?}"),
    }
}

/// Assert an `Error::Input` whose message contains `needle`.
#[track_caller]
fn assert_input_err<T: std::fmt::Debug>(r: robokrige::Result<T>, needle: &str) {
    match r {
        Err(Error::Input {
            source_name,
            message,
        }) => {
            assert!(!source_name.is_empty());
            assert!(message.contains(needle), "'{message}' lacks '{needle}'");
        }
        other => panic!("expected Error::Input, got {other:?}"),
    }
}

/// A unique path in the system temp directory.
fn temp_path(tag: &str) -> PathBuf {
    let nanos = std::time::SystemTime::now()
        .duration_since(std::time::UNIX_EPOCH)
        .map_or(0, |d| d.as_nanos());
    std::env::temp_dir().join(format!(
        "robokrige_{tag}_{}_{nanos}.csv",
        std::process::id()
    ))
}

const FULL: &str = "\
id,q1,q2,dir1,dir2,ex,ey,ez,x,y,z,temp_c,note
a,10,20,1,-1,0.1,0.2,0.3,100,200,300,21.5,ok
b,11.5,19,-1,-1,-0.1,0,1e-3,101,201,301,,\"warm, humid\"
c,12,19,+1,1.0,0,0,0,102,202,302,22,x
";

// ----- valid input ----------------------------------------------------------

#[test]
fn reads_every_column_kind() {
    let d = read(FULL).unwrap();
    assert_eq!((d.len(), d.n_joints()), (3, 2));
    assert!(!d.is_empty());
    assert_eq!(d.source, "test.csv");
    assert_eq!(d.q[1], vec![11.5, 19.0]);
    assert_eq!(
        d.dir,
        vec![vec![1.0, -1.0], vec![-1.0, -1.0], vec![1.0, 1.0]]
    );
    assert_eq!(d.dir_source, DirSource::Given);
    assert_eq!(d.errors_or_err().unwrap()[1], [-0.1, 0.0, 1e-3]);
    assert_eq!(d.positions.as_ref().unwrap()[2], [102.0, 202.0, 302.0]);
    assert_eq!(d.ids, Some(vec!["a".into(), "b".into(), "c".into()]));
    let t = d.covariate("temp_c").unwrap();
    assert_eq!((t.values[0], t.values[2], t.missing), (21.5, 22.0, 1));
    assert!(t.values[1].is_nan());
    assert!(d.covariate("note").is_none());
    assert_eq!(d.text.len(), 1);
    assert_eq!(d.text[0].values, vec!["ok", "warm, humid", "x"]);
    d.validate().unwrap();
}

#[test]
fn pose_list_derives_directions() {
    let d = read("q1,q2\n0,0\n1,0\n0.5,2\n").unwrap();
    assert_eq!(d.dir_source, DirSource::Derived);
    assert_eq!(d.dir, vec![vec![1.0, 1.0], vec![1.0, 1.0], vec![-1.0, 1.0]]);
    assert!(d.errors.is_none() && d.positions.is_none() && d.ids.is_none());
    assert_input_err(d.errors_or_err(), "no ex,ey,ez");
}

#[test]
fn accepts_all_direction_spellings() {
    let d = read("q1,dir1\n0,1\n0,+1\n0,-1\n0,1.0\n0,-1.0\n").unwrap();
    let dirs: Vec<f64> = d.dir.iter().map(|r| r[0]).collect();
    assert_eq!(dirs, vec![1.0, 1.0, -1.0, 1.0, -1.0]);
}

#[test]
fn accepts_bom_whitespace_crlf_and_trailing_blank_lines() {
    let d = read("\u{feff}q1 , q2,ex,ey,ez\r\n 1 ,2, 0,0,0\r\n3,4,0,0,0\r\n\r\n\n").unwrap();
    assert_eq!(d.q, vec![vec![1.0, 2.0], vec![3.0, 4.0]]);
}

#[test]
fn whitespace_only_lines_count_as_blank() {
    let d = read("q1,q2\n1,2\n   \n3,4\n \t\n").unwrap();
    assert_eq!(d.len(), 2);
    assert_csv_err("q1,q2\n  \n1,2\n3\n", 4, None, "row has 1 cells");
}

#[test]
fn leading_blank_lines_shift_the_header_line() {
    let d = read("\n\nq1\n1\n").unwrap();
    assert_eq!(d.q, vec![vec![1.0]]);
    assert_csv_err("\nq1,q1\n1,2\n", 2, Some("q1"), "appears twice");
}

#[test]
fn invalid_utf8_is_a_csv_error() {
    match read_csv_from(&b"q1,note\n1,ok\n2,\xff\n"[..], "test.csv") {
        Err(Error::Csv { line, .. }) => assert_eq!(line, 3),
        other => panic!("expected Error::Csv, got {other:?}"),
    }
    match read_csv_from(&b"q1,note\r\n1,ok\r\n\r\n2,\xff\r\n"[..], "test.csv") {
        Err(Error::Csv { line, .. }) => assert_eq!(line, 4),
        other => panic!("expected Error::Csv, got {other:?}"),
    }
}

#[test]
fn column_order_in_file_does_not_matter() {
    let d = read("ez,q2,x,dir2,y,q1,dir1,ey,z,ex\n3,2,10,-1,20,1,1,2,30,1\n").unwrap();
    assert_eq!(d.q[0], vec![1.0, 2.0]);
    assert_eq!(d.dir[0], vec![1.0, -1.0]);
    assert_eq!(d.errors.unwrap()[0], [1.0, 2.0, 3.0]);
    assert_eq!(d.positions.unwrap()[0], [10.0, 20.0, 30.0]);
}

#[test]
fn non_numeric_covariate_becomes_text_and_nan_covariate_too() {
    let d = read("q1,batch,flag\n1,7,nan\n2,A,1\n3,,\n").unwrap();
    assert!(d.covariates.is_empty());
    let names: Vec<&str> = d.text.iter().map(|t| t.name.as_str()).collect();
    assert_eq!(names, vec!["batch", "flag"]);
    assert_eq!(d.text[0].values, vec!["7", "A", ""]);
}

#[test]
fn all_empty_covariate_is_numeric_and_missing() {
    let d = read("q1,temp_c\n1,\n2,\n").unwrap();
    let c = d.covariate("temp_c").unwrap();
    assert_eq!(c.missing, 2);
    assert!(c.values.iter().all(|v| v.is_nan()));
}

#[test]
fn line_numbers_count_skipped_blank_lines() {
    assert_csv_err(
        "q1\n1\n\n2\nabc\n",
        5,
        Some("q1"),
        "expected a number, found 'abc'",
    );
    assert_csv_err("q1\n1\n\n\nabc\n", 5, Some("q1"), "found 'abc'");
    assert_csv_err("q1\r\n1\r\n\r\nabc\r\n", 4, Some("q1"), "found 'abc'");
    assert_csv_err("q1\r1\r\rabc\r", 4, Some("q1"), "found 'abc'");
}

#[test]
fn line_numbers_count_lines_inside_quoted_cells() {
    assert_csv_err(
        "q1,note\n1,\"two\nlines\"\n\nx,y\n",
        5,
        Some("q1"),
        "found 'x'",
    );
}

// ----- whole-input errors ---------------------------------------------------

#[test]
fn empty_file_is_an_input_error() {
    assert_input_err(read(""), "empty");
    assert_input_err(read("\u{feff}"), "empty");
}

#[test]
fn header_only_is_an_input_error() {
    assert_input_err(read("q1,q2,ex,ey,ez\n"), "no data rows");
    assert_input_err(read("q1,q2\n\n\n"), "no data rows");
}

#[test]
fn missing_q1_is_an_input_error_listing_columns() {
    assert_input_err(read("a,b,ex\n1,2,3\n"), "no q1 column");
    assert_input_err(read("q2,q3,temp\n1,2,3\n"), "found: q2, q3, temp");
}

#[test]
fn missing_file_is_an_io_error() {
    let path = temp_path("absent");
    assert!(matches!(read_csv(&path), Err(Error::Io { .. })));
}

// ----- header errors --------------------------------------------------------

#[test]
fn gap_in_joint_columns() {
    assert_csv_err("q1,q2,q4\n1,2,3\n", 1, Some("q4"), "q3 is missing");
}

#[test]
fn malformed_joint_numbers() {
    assert_csv_err("q1,q0\n1,2\n", 1, Some("q0"), "numbered from 1");
    assert_csv_err("q1,dir01\n1,1\n", 1, Some("dir01"), "without leading zeros");
}

#[test]
fn partial_direction_columns() {
    assert_csv_err("q1,q2,q3,dir1,dir3\n1,2,3,1,1\n", 1, None, "dir2");
    assert_csv_err(
        "q1,dir1,dir2\n1,1,1\n",
        1,
        Some("dir2"),
        "no joint column q2",
    );
}

#[test]
fn partial_error_triplet() {
    assert_csv_err("q1,ex,ez\n1,2,3\n", 1, None, "found ex,ez but not ey");
}

#[test]
fn partial_position_triplet() {
    assert_csv_err(
        "q1,x,y,ex,ey,ez\n1,2,3,0,0,0\n",
        1,
        None,
        "found x,y but not z",
    );
}

#[test]
fn duplicate_header_name() {
    assert_csv_err("q1,q2,temp,q2\n1,2,3,4\n", 1, Some("q2"), "appears twice");
    assert_csv_err("q1,temp,temp\n1,2,3\n", 1, Some("temp"), "appears twice");
}

#[test]
fn empty_header_cell() {
    assert_csv_err("q1,q2,\n1,2,\n", 1, None, "header cell 3 is empty");
}

// ----- cell errors ----------------------------------------------------------

#[test]
fn non_numeric_cells() {
    assert_csv_err(
        "q1,q2\n1,2\n1,abc\n",
        3,
        Some("q2"),
        "expected a number, found 'abc'",
    );
    assert_csv_err("q1,ex,ey,ez\n1,0,1 mm,0\n", 2, Some("ey"), "found '1 mm'");
    assert_csv_err("q1,x,y,z\n1,0,0,z0\n", 2, Some("z"), "found 'z0'");
}

#[test]
fn nan_and_inf_are_rejected() {
    assert_csv_err("q1,q2\n1,NaN\n", 2, Some("q2"), "NaN/inf");
    assert_csv_err("q1,q2\n1,2\nnan,2\n", 3, Some("q1"), "NaN/inf");
    assert_csv_err("q1,ex,ey,ez\n1,0,0,inf\n", 2, Some("ez"), "NaN/inf");
    assert_csv_err(
        "q1,x,y,z\n1,-Infinity,0,0\n",
        2,
        Some("x"),
        "remove or fix the row",
    );
}

#[test]
fn bad_directions() {
    assert_csv_err(
        "q1,dir1\n1,0.5\n",
        2,
        Some("dir1"),
        "direction must be +1 or -1, found 0.5",
    );
    assert_csv_err("q1,dir1\n1,1\n2,0\n", 3, Some("dir1"), "found 0");
    assert_csv_err("q1,dir1\n1,fwd\n", 2, Some("dir1"), "found fwd");
    assert_csv_err("q1,dir1\n1,nan\n", 2, Some("dir1"), "+1 or -1");
    assert_csv_err("q1,dir1\n1,\n", 2, Some("dir1"), "missing value");
}

#[test]
fn ragged_rows() {
    assert_csv_err(
        "q1,q2,q3\n1,2,3\n1,2\n",
        3,
        None,
        "row has 2 cells but the header has 3",
    );
    assert_csv_err(
        "q1,q2\n1,2,3\n",
        2,
        None,
        "row has 3 cells but the header has 2",
    );
}

#[test]
fn empty_required_cells() {
    assert_csv_err("q1,q2\n1,2\n1,\n", 3, Some("q2"), "missing value");
    assert_csv_err("q1,ex,ey,ez\n1,,0,0\n", 2, Some("ex"), "missing value");
    assert_csv_err("q1,x,y,z\n1,0,0, \n", 2, Some("z"), "missing value");
}

#[test]
fn error_display_names_file_line_and_column() {
    let e = read("q1,q2\n1,x\n").unwrap_err();
    assert_eq!(
        e.to_string(),
        "test.csv:2: column 'q2': expected a number, found 'x'"
    );
}

// ----- in-memory datasets ---------------------------------------------------

#[test]
fn from_poses_derives_or_takes_directions() {
    let q = vec![vec![0.0, 1.0], vec![-1.0, 1.0]];
    let d = Dataset::from_poses("<memory>", q.clone(), None).unwrap();
    assert_eq!(d.dir_source, DirSource::Derived);
    assert_eq!(d.dir, vec![vec![1.0, 1.0], vec![-1.0, 1.0]]);
    let dir = vec![vec![-1.0, -1.0], vec![1.0, -1.0]];
    let d = Dataset::from_poses("<memory>", q, Some(dir.clone())).unwrap();
    assert_eq!((d.dir_source, d.dir), (DirSource::Given, dir));
}

#[test]
fn from_poses_rejects_bad_shapes() {
    assert_input_err(Dataset::from_poses("m", vec![], None), "no poses");
    assert_input_err(
        Dataset::from_poses("m", vec![vec![1.0], vec![1.0, 2.0]], None),
        "row 1",
    );
    assert_input_err(
        Dataset::from_poses("m", vec![vec![f64::NAN]], None),
        "NaN/inf",
    );
    assert_input_err(
        Dataset::from_poses("m", vec![vec![1.0]], Some(vec![vec![0.5]])),
        "found 0.5",
    );
    assert_input_err(
        Dataset::from_poses("m", vec![vec![1.0]], Some(vec![])),
        "dir has 0 rows",
    );
}

#[test]
fn validate_catches_inconsistent_columns() {
    let good = read(FULL).unwrap();
    let mut d = good.clone();
    d.errors.as_mut().unwrap().pop();
    assert_input_err(d.validate(), "errors has 2 rows");
    let mut d = good.clone();
    d.positions.as_mut().unwrap()[0][1] = f64::INFINITY;
    assert_input_err(d.validate(), "positions row 0");
    let mut d = good.clone();
    d.covariates[0].missing = 0;
    assert_input_err(d.validate(), "missing");
    let mut d = good.clone();
    d.text[0].name = "q3".into();
    assert_input_err(d.validate(), "reserved");
    let mut d = good.clone();
    d.text[0].name = "temp_c".into();
    assert_input_err(d.validate(), "used twice");
    let mut d = good;
    d.ids.as_mut().unwrap().push("d".into());
    assert_input_err(d.validate(), "ids has 4");
}

#[test]
fn writing_an_invalid_dataset_fails_without_output() {
    let mut d = read(FULL).unwrap();
    d.dir[0][0] = 0.0;
    let mut out = Vec::new();
    assert!(matches!(
        write_csv_to(&mut out, &d),
        Err(Error::Input { .. })
    ));
    assert!(out.is_empty());
}

// ----- writing and round trips ----------------------------------------------

#[test]
fn writes_documented_column_order_and_formats() {
    let d = read(FULL).unwrap();
    let mut out = Vec::new();
    write_csv_to(&mut out, &d).unwrap();
    let text = String::from_utf8(out).unwrap();
    let mut lines = text.lines();
    assert_eq!(
        lines.next(),
        Some("id,q1,q2,dir1,dir2,ex,ey,ez,x,y,z,temp_c,note")
    );
    assert_eq!(
        lines.next(),
        Some("a,10,20,1,-1,0.1,0.2,0.3,100,200,300,21.5,ok")
    );
    assert_eq!(
        lines.next(),
        Some("b,11.5,19,-1,-1,-0.1,0,0.001,101,201,301,,\"warm, humid\"")
    );
}

#[test]
fn round_trip_in_memory_is_exact() {
    let d = read(FULL).unwrap();
    let mut out = Vec::new();
    write_csv_to(&mut out, &d).unwrap();
    assert_eq!(read_csv_from(out.as_slice(), "test.csv").unwrap(), d);
}

#[test]
fn round_trip_derived_directions_become_given() {
    let q = vec![
        vec![0.1 + 0.2, -1e-12],
        vec![1.0 / 3.0, 987_654.321_012_345_6],
        vec![-0.0, 5.0],
    ];
    let mut d = Dataset::from_poses("<memory>", q, None).unwrap();
    d.errors = Some(vec![[1.0 / 7.0, 0.0, -2.5e-9]; 3]);
    let mut out = Vec::new();
    write_csv_to(&mut out, &d).unwrap();
    let back = read_csv_from(out.as_slice(), "<memory>").unwrap();
    assert_eq!(back.dir_source, DirSource::Given);
    d.dir_source = DirSource::Given;
    assert_eq!(back, d);
}

#[test]
fn round_trip_through_a_temp_file() {
    let d = read(FULL).unwrap();
    let path = temp_path("roundtrip");
    write_csv(&path, &d).unwrap();
    let back = read_csv(&path);
    let _ = std::fs::remove_file(&path);
    let mut back = back.unwrap();
    assert_eq!(back.source, path.display().to_string());
    back.source = d.source.clone();
    assert_eq!(back, d);
}

// ----- the public UR10 data set ---------------------------------------------

#[test]
fn reads_ipa_ur10_series_c_if_present() {
    let path = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../shared/data/ipa-ur10/series_c_random_poses.csv");
    if !path.exists() {
        eprintln!("skipped: {} absent", path.display());
        return;
    }
    let d = read_csv(&path).unwrap();
    assert_eq!((d.len(), d.n_joints()), (2773, 6));
    assert_eq!(d.dir_source, DirSource::Given);
    assert_eq!(d.errors_or_err().unwrap().len(), 2773);
    let temp = d.covariate("temp_c").unwrap();
    assert_eq!(temp.values.len(), 2773);
    assert!(temp.values.iter().all(|t| (0.0..60.0).contains(t)));
    d.validate().unwrap();
}
