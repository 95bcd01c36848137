//! The Touchstone reader against scikit-rf: every fixture of `data/touchstone/zoo/`
//! (written by `scripts/make_skrf_fixture.py`: 1- to 4-port, RI/MA/DB, Hz..GHz, v2, HFSS port
//! impedances, `-inf` dB, noise blocks, BOM, Latin-1, CR endings, per-port and complex z0)
//! reads to the values scikit-rf reads from it; refusals name the file, the line and the
//! reason; the parameter is selected by name.

use crate::common::root;
use num_complex::Complex64;
use pradar::campaign::touchstone::{read_touchstone, SParam};

/// Numbers stored as `repr()` strings (`str::parse` is correctly rounded; serde_json's
/// default float parser is not).
fn floats(v: &serde_json::Value, k: &str) -> Vec<f64> {
    v[k].as_array()
        .unwrap()
        .iter()
        .map(|x| x.as_str().unwrap().parse().unwrap())
        .collect()
}

#[test]
fn zoo_reads_as_scikit_rf_reads_it() {
    let dir = root().join("data/touchstone/zoo");
    let expected: serde_json::Map<String, serde_json::Value> =
        serde_json::from_str(&std::fs::read_to_string(dir.join("zoo_expected.json")).unwrap())
            .unwrap();
    assert!(expected.len() >= 23, "{} fixtures", expected.len());
    let mut worst = 0.0f64;
    for (name, e) in &expected {
        let net = read_touchstone(&dir.join(name)).unwrap_or_else(|err| panic!("{err}"));
        let ports = e["ports"].as_u64().unwrap() as usize;
        assert_eq!(net.ports, ports, "{name}");
        assert_eq!(net.freq_hz, floats(e, "f"), "{name}: frequencies");
        let (re, im) = (floats(e, "s_re"), floats(e, "s_im"));
        assert_eq!(net.s.len(), re.len(), "{name}");
        for (k, got) in net.s.iter().enumerate() {
            let want = Complex64::new(re[k], im[k]);
            let d = (got - want).norm();
            if name.contains("_ri") || name.contains("v2_p2") {
                // RI: the printed decimals, parsed the same way
                assert_eq!(*got, want, "{name}[{k}]");
            }
            // MA/DB: the printed 17 digits through cos/sin and 10^(a/20) (libm and numpy
            // differ by a few ulp)
            assert!(d <= 2e-15 * want.norm(), "{name}[{k}]: {got} vs {want}");
            worst = worst.max(d / want.norm().max(1e-300));
        }
        let (zr, zi) = (floats(e, "z0_re"), floats(e, "z0_im"));
        let z: Vec<Complex64> = zr
            .iter()
            .zip(&zi)
            .map(|(&a, &b)| Complex64::new(a, b))
            .collect();
        assert_eq!(net.z0_ohm, z, "{name}: reference impedance");
        assert_eq!(
            !net.notes.is_empty(),
            e["noise"].as_bool().unwrap(),
            "{name}: {:?}",
            net.notes
        );
    }
    eprintln!(
        "{} fixtures: worst relative |dS| vs scikit-rf {worst:.2e}",
        expected.len()
    );
}

#[test]
fn parameter_selection_by_name() {
    let dir = root().join("data/touchstone/zoo");
    let p4 = dir.join("p4_ri.s4p");
    let net = read_touchstone(&p4).unwrap();
    let s34: SParam = "S34".parse().unwrap();
    let got = net.param(s34, &p4).unwrap();
    for (k, v) in got.iter().enumerate() {
        assert_eq!(*v, net.get(k, 2, 3));
    }
    // the written value S_ij = (0.1 + 0.05 i + 0.01 j)·(1 + 0.02 k)·e^{-j(0.3 i + 0.2 j) k}
    let want = (0.1 + 0.05 * 3.0 + 0.01 * 4.0) * 1.02 * Complex64::from_polar(1.0, -(0.9 + 0.8));
    assert!((got[1] - want).norm() < 1e-15, "{} vs {want}", got[1]);
    let e = net
        .param("S51".parse().unwrap(), &p4)
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("p4_ri.s4p: parameter S51 does not exist in a 4-port file"),
        "{e}"
    );
    let p1 = dir.join("p1_ri.s1p");
    let one = read_touchstone(&p1).unwrap();
    assert_eq!(
        one.freq_hz.len(),
        6,
        "six points: the old reader regrouped them as two"
    );
    let e = one.param(SParam::S21, &p1).unwrap_err().to_string();
    assert!(e.contains("set [sweeps] parameter = \"S11\""), "{e}");
}

#[test]
fn refusals_name_file_line_and_reason() {
    let src = root().join("data/touchstone/zoo");
    let tmp = tempfile::tempdir().unwrap();
    let read = |name: &str, text: &str| -> String {
        let p = tmp.path().join(name);
        std::fs::write(&p, text).unwrap();
        read_touchstone(&p).unwrap_err().to_string()
    };
    let two = std::fs::read_to_string(src.join("p2_ri.s2p")).unwrap();
    let one = std::fs::read_to_string(src.join("p1_ri.s1p")).unwrap();
    // (file, text, what the one line must say); lines counted in the skrf header
    let cases: Vec<(&str, String, &str)> = vec![
        ("as_one.s1p", two.clone(), "line 4: more numbers after a complete point: a 1-port point has 3 numbers"),
        ("as_four.s4p", two.clone(), "line 5: 9 numbers on a continuation line (pairs expected): a 4-port point has 33 numbers"),
        ("as_two.s2p", one.clone(), "line 6: 3 numbers on a continuation line"),
        ("nan.s2p", two.replacen("0.16000000000000003", "NaN", 1), "line 4: non-finite value `NaN`"),
        ("word.s2p", two.replacen("0.17", "0.1.7", 1), "line 4: cannot parse `0.1.7` as a number"),
        ("z.s2p", two.replacen("# Hz S RI", "# Hz Z RI", 1), "line 2: parameter type `Z` not supported (only S)"),
        // (in a v1 two-port file a falling row of five numbers starts the noise block, as
        // in skrf; a falling row of S data is out of order)
        ("down.s1p", {
            let mut l: Vec<&str> = one.lines().collect();
            l.swap(4, 5);
            l.join("\n")
        }, "line 6: frequency 57500000000 Hz not increasing"),
        ("swapped.s2p", {
            let mut l: Vec<&str> = two.lines().collect();
            l.swap(4, 5);
            l.join("\n")
        }, "line 6: frequency 58700000000 Hz not increasing (below 59900000000 Hz of line 5): the rows stop increasing here (swapped or reversed?)"),
        ("reversed.s2p", {
            let l: Vec<&str> = two.lines().collect();
            let (head, rows) = l.split_at(3);
            head.iter().chain(rows.iter().rev()).copied().collect::<Vec<_>>().join("\n")
        }, "line 5: frequency"),
        ("no_order.ts", "[Version] 2.0\n# GHz S RI\n[Number of Ports] 2\n[Network Data]\n1 0 0 1 0 1 0 0 0\n[End]\n".into(), "line 5: [Two-Port Data Order] missing"),
        ("v1.txt", two.clone(), "must be named .sNp"),
        ("mm.ts", "[Version] 2.0\n# GHz S RI\n[Number of Ports] 4\n[Mixed-Mode Order] D2,1 C2,1 D4,3 C4,3\n".into(), "line 4: mixed-mode data"),
        ("nf.ts", "[Version] 2.0\n# GHz S RI\n[Number of Ports] 1\n[Number of Frequencies] 3\n[Network Data]\n1 0 0\n2 0 0\n[End]\n".into(), "line 4: [Number of Frequencies] 3 but the file holds 2 points"),
    ];
    for (name, text, want) in cases {
        let e = read(name, &text);
        assert!(!e.contains('\n'), "one line: {e}");
        assert!(
            e.contains(name) && e.contains(want),
            "{name}: `{e}` should say `{want}`"
        );
    }
}
