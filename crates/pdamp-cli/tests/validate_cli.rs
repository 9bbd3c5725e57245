//! `pdamp validate --quick`: writes the validation table into `--out`, prints its counts, and
//! its `validation.md` is the committed docs/validation.md; a second run into the same
//! directory needs `--overwrite`.

use std::process::Command;

fn pdamp(args: &[&str]) -> std::process::Output {
    Command::new(env!("CARGO_BIN_EXE_pdamp"))
        .arg("--quiet")
        .args(args)
        .output()
        .unwrap()
}

#[test]
fn validate_quick_writes_the_table_of_the_docs() {
    let dir = std::env::temp_dir().join(format!("pdamp-validate-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    let out = dir.to_str().unwrap();
    let o = pdamp(&["validate", "--quick", "--out", out]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(o.status.success(), "{err}");
    let v: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    let rows = v["rows"].as_u64().unwrap();
    assert!(rows >= 80, "{v}");
    assert_eq!(v["failed"], 0, "{v}");
    let sum: u64 = ["reproduced", "not_reproduced", "failed", "not_run"]
        .iter()
        .map(|k| v[k].as_u64().unwrap())
        .sum();
    assert_eq!(sum, rows);
    let md = std::fs::read_to_string(dir.join("validation.md")).unwrap();
    let docs = std::fs::read_to_string(
        std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../docs/validation.md"),
    )
    .unwrap();
    assert_eq!(md, docs, "docs/validation.md is stale");
    let csv = std::fs::read_to_string(dir.join("validation.csv")).unwrap();
    assert_eq!(csv.lines().count() as u64, rows + 1);
    assert!(dir.join("provenance.json").is_file());
    // The results of a run are not replaced silently.
    let again = pdamp(&["validate", "--quick", "--out", out]);
    assert_eq!(again.status.code(), Some(1));
    let o = pdamp(&["validate", "--quick", "--out", out, "--overwrite"]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn validate_only_runs_the_named_rows_and_refuses_a_prefix_without_rows() {
    let dir = std::env::temp_dir().join(format!("pdamp-validate-only-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    let out = dir.to_str().unwrap();
    let o = pdamp(&["validate", "--only", "ch6.tab6_2,paper.tabA2", "--out", out]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let v: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    let csv = std::fs::read_to_string(dir.join("validation.csv")).unwrap();
    let ids: Vec<&str> = csv
        .lines()
        .skip(1)
        .map(|l| l.split(',').next().unwrap())
        .collect();
    assert_eq!(v["rows"].as_u64().unwrap() as usize, ids.len());
    assert!(ids.len() >= 5, "{ids:?}");
    assert!(
        ids.iter()
            .all(|id| id.starts_with("ch6.tab6_2") || id.starts_with("paper.tabA2")),
        "{ids:?}"
    );
    let _ = std::fs::remove_dir_all(&dir);
    let o = pdamp(&["validate", "--only", "ch9", "--out", out]);
    assert_eq!(o.status.code(), Some(1));
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        err.contains("--only ch9: no row id starts with 'ch9'"),
        "{err}"
    );
    assert!(!dir.exists(), "nothing is written for a refused run");
}
