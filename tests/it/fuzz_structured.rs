//! Issue 25, structure-aware fuzzing (`fuzz/fuzz_targets/*_structured.rs`, `fuzz/RESULTS.md`):
//! what the fuzzers found, and generated files kept as regression inputs. Each runs the
//! binary under the 4 GiB address-space cap and the 20 s limit of `budgets_files`.

use crate::budgets_files::{read_within, refused};
use std::path::{Path, PathBuf};

fn fuzz_file(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/data/fuzz")
        .join(name)
}

/// Found by xml_structured: 80,544 nested `<Row>` elements (886 kB) took 34 s in the fuzzer
/// and 2.8 s in release, each row collecting its descendants' cells (quadratic).
#[test]
fn kinovea_xml_of_80544_nested_rows_found_by_fuzzing_is_refused_quickly() {
    let run = refused(
        &fuzz_file("kinovea_xml_80544_nested_rows.xml"),
        &["--format", "kinovea"],
        &["no frames"],
    );
    assert!(run.seconds < 2.0, "{:.1} s", run.seconds);
}

/// The same shape 400,000 deep (4.4 MB of the 64 MiB a spreadsheet may have) took 95 s.
#[test]
fn kinovea_xml_rows_nested_400000_deep_are_read_in_linear_time() {
    let dir = tempfile::tempdir().unwrap();
    let n = 400_000;
    let text = format!(
        "<?xml version=\"1.0\"?>\n<?mso-application progid=\"Excel.Sheet\"?>\n<Workbook>{}<Cell><Data>1</Data></Cell>{}</Workbook>\n",
        "<Row>".repeat(n),
        "</Row>".repeat(n)
    );
    let f = dir.path().join("nested_rows.xml");
    std::fs::write(&f, text).unwrap();
    let run = read_within(&f, &["--format", "kinovea"], 10.0);
    assert_eq!(run.code, Some(2), "{}", run.stderr);
    assert!(run.stderr.contains("nested_rows.xml"), "{}", run.stderr);
}

/// Made by mcap_structured (lz4 chunks, a CDR `tf2_msgs/msg/TFMessage` channel whose
/// transforms make a cycle through `base_link`): the /tf cycle check, which no other test
/// reaches, ends the read with a message.
#[test]
fn mcap_tf_transforms_in_a_cycle_made_by_fuzzing_are_a_clear_error() {
    refused(
        &fuzz_file("mcap_structured_tf_cycle.mcap"),
        &[],
        &["a cycle through frame \"base_link\""],
    );
}

/// Made by hdf5_structured from `fuzz/seeds/sleap_chunk_gzip_shuffle.h5` (the chunked SLEAP
/// tracks, one filter id of the pipeline turned into Fletcher-32): the chunk's checksum does
/// not match, which hdf5-reader reports and the reader passes on.
#[test]
fn sleap_h5_chunk_failing_its_fletcher32_checksum_is_a_clear_error() {
    refused(
        &fuzz_file("hdf5_structured_sleap_fletcher32_mismatch.h5"),
        &["--fps", "30"],
        &["tracks", "checksum mismatch"],
    );
}

/// Found by pickle_structured: a label pickle of empty tuples each put under the same memo
/// id, `(l(tp65284\na(tp65284\na...a.`, passes the label-pickle check (a list of tuples) and
/// is refused by serde-pickle's decoder; written here into the repo's DeepLabCut table in
/// place of its labels.
#[test]
fn dlc_h5_label_pickle_reputting_one_memo_id_is_refused_by_the_decoder() {
    let src = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/data/dlc_reachingvideo1shortDLC_resnet50_TESTNov4shuffle1_10.h5");
    let mut bytes = std::fs::read(src).unwrap();
    let find = |from: usize, what: &[u8]| {
        from + bytes[from..]
            .windows(what.len())
            .position(|w| w == what)
            .unwrap()
    };
    let start = find(0, b"(lp0\n(VDLC_resnet50");
    let end = find(start, b"\na.") + 3;
    let mut pickle = b"(l".to_vec();
    for _ in 0..11 {
        pickle.extend_from_slice(b"(tp65284\na");
    }
    pickle.push(b'.');
    assert!(pickle.len() <= end - start);
    pickle.resize(end - start, 0);
    bytes[start..end].copy_from_slice(&pickle);
    let dir = tempfile::tempdir().unwrap();
    let f = dir.path().join("reput_memo.h5");
    std::fs::write(&f, bytes).unwrap();
    refused(&f, &["--fps", "30"], &["values_block_0_kind"]);
}
