//! Property tests: reading a scene never panics, whatever the text and the overrides.
//!
//! `Scene::from_toml_str` must return `Ok` or `Err` for any input; an `Err` displays as a
//! single line (the CLI prints it as its one line of stderr); an `Ok` scene written back
//! with `to_file` validates to the same scene.

use proptest::prelude::*;
use stickslip::Scene;
use stickslip_testkit::FIG1;

/// Checks the properties for one input.
fn check(text: &str, overrides: &[String]) -> Result<(), TestCaseError> {
    match Scene::from_toml_str(text, "fuzz.toml", "fuzz", overrides) {
        Ok(scene) => {
            let again = scene.with_overrides(&[]);
            prop_assert!(
                again.is_ok(),
                "a valid scene written back is refused: {:?}",
                again.err().map(|e| e.to_string())
            );
            // What `validate` and `stability` print from a valid scene never panics either.
            let a = stickslip::engine::fixed::stability::analyse(&scene);
            prop_assert!(!stickslip::cli::stability::table(&a, &scene.name).is_empty());
            prop_assert!(!stickslip::cli::stability::validate_block(&a, scene.run.engine).is_empty());
            let _ = stickslip::cli::stability::warning(&scene);
            prop_assert_eq!(again.unwrap(), scene);
        }
        Err(e) => {
            let msg = e.to_string();
            prop_assert!(!msg.is_empty());
            prop_assert!(!msg.contains(['\n', '\r']), "error message is not one line: {msg:?}");
        }
    }
    Ok(())
}

const SECTIONS: &[&str] = &["junctions", "plate", "run", "fixed", "exact", "output", "junction", "", "run.sub"];
const KEYS: &[&str] = &[
    "n",
    "bond",
    "force_law",
    "kappa",
    "l0",
    "lambda",
    "reattach",
    "k0",
    "kon0",
    "tau0",
    "alpha",
    "dx",
    "temperature",
    "initial",
    "mass",
    "eta",
    "k",
    "v",
    "engine",
    "t_end",
    "t_warmup",
    "seed",
    "dt",
    "rng",
    "flip",
    "integrator",
    "rtol",
    "atol",
    "sample_dt",
    "trace",
    "events",
    "plot",
    "unknown",
    "\"a\\nb\"",
];
const VALUES: &[&str] = &[
    "0",
    "1",
    "-1",
    "300",
    "0.0",
    "-0.0",
    "1e-320",
    "1e308",
    "1.7976931348623157e308",
    "nan",
    "+inf",
    "-inf",
    "9223372036854775807",
    "-9223372036854775808",
    "2147483646",
    "2147483647",
    "4294967296",
    "18446744073709551615",
    "true",
    "false",
    "\"strong\"",
    "\"weak\"",
    "\"tilted\"",
    "\"linear\"",
    "\"fixed\"",
    "\"exact\"",
    "\"park-miller\"",
    "\"pcg\"",
    "\"as-printed\"",
    "\"stationary\"",
    "\"medium\"",
    "\"\"",
    "\"\\n\"",
    "[]",
    "[1, 2]",
    "{}",
    "{ a = 1 }",
    "1979-05-27T07:32:00Z",
    "0x1f",
    "1_000",
    "'x'",
];

/// TOML-like text built from the scene's own sections, keys and tricky values.
pub(crate) fn scene_like() -> impl Strategy<Value = String> {
    let line = prop_oneof![
        prop::sample::select(SECTIONS).prop_map(|s| format!("[{s}]")),
        (prop::sample::select(KEYS), prop::sample::select(VALUES)).prop_map(|(k, v)| format!("{k} = {v}")),
        ".{0,20}",
    ];
    prop::collection::vec(line, 0..30).prop_map(|lines| lines.join("\n"))
}

/// One edit of a text: delete, insert or replace a run of characters.
#[derive(Clone, Debug)]
enum Edit {
    Delete { at: usize, len: usize },
    Insert { at: usize, s: String },
    Replace { at: usize, s: String },
}

fn edit() -> impl Strategy<Value = Edit> {
    let snippet = prop_oneof![".{0,6}", prop::sample::select(VALUES).prop_map(str::to_string), "[=\\[\\]\"#.\n-]{1,3}"];
    prop_oneof![
        (any::<usize>(), 0usize..8).prop_map(|(at, len)| Edit::Delete { at, len }),
        (any::<usize>(), snippet.clone()).prop_map(|(at, s)| Edit::Insert { at, s }),
        (any::<usize>(), snippet).prop_map(|(at, s)| Edit::Replace { at, s }),
    ]
}

/// Applies edits on character positions, so the result stays valid UTF-8.
fn mutate(text: &str, edits: &[Edit]) -> String {
    let mut chars: Vec<char> = text.chars().collect();
    for e in edits {
        let at = |a: usize| {
            if chars.is_empty() { 0 } else { a % (chars.len() + 1) }
        };
        match e {
            Edit::Delete { at: a, len } => {
                let i = at(*a);
                let j = (i + len).min(chars.len());
                chars.drain(i..j);
            }
            Edit::Insert { at: a, s } => {
                let i = at(*a);
                chars.splice(i..i, s.chars());
            }
            Edit::Replace { at: a, s } => {
                let i = at(*a);
                let j = (i + s.chars().count()).min(chars.len());
                chars.splice(i..j, s.chars());
            }
        }
    }
    chars.into_iter().collect()
}

/// A `--set` assignment, well-formed or not.
fn assignment() -> impl Strategy<Value = String> {
    prop_oneof![
        (prop::sample::select(SECTIONS), prop::sample::select(KEYS), prop::sample::select(VALUES))
            .prop_map(|(s, k, v)| format!("{s}.{k}={v}")),
        (prop::sample::select(SECTIONS), prop::sample::select(KEYS), "[a-z0-9.\\-]{0,8}")
            .prop_map(|(s, k, v)| format!("{s}.{k}={v}")),
        ".{0,24}",
    ]
}

/// `cases` cases (or `PROPTEST_CASES`) from the fixed seed `seed` (or `PROPTEST_RNG_SEED`):
/// CI runs the same cases every time. Failures are shrunk and printed, not persisted.
pub(crate) fn fuzz_config(cases: u32, seed: u64) -> ProptestConfig {
    let env = |name: &str| std::env::var(name).ok().and_then(|s| s.parse().ok());
    ProptestConfig {
        cases: env("PROPTEST_CASES").map_or(cases, |c: u64| c as u32),
        failure_persistence: None,
        rng_seed: proptest::test_runner::RngSeed::Fixed(env("PROPTEST_RNG_SEED").unwrap_or(seed)),
        ..ProptestConfig::default()
    }
}

proptest! {
    // 2048 cases each by default; PROPTEST_CASES=100000 (and another PROPTEST_RNG_SEED)
    // for a long hunt. Add failures to `regressions` below rather than to a file.
    #![proptest_config(fuzz_config(2048, 20261121))]

    #[test]
    fn arbitrary_text_never_panics(text in ".{0,200}") {
        check(&text, &[])?;
    }

    #[test]
    fn arbitrary_bytes_as_text_never_panic(bytes in prop::collection::vec(any::<u8>(), 0..200)) {
        check(&String::from_utf8_lossy(&bytes), &[])?;
    }

    #[test]
    fn scene_like_text_never_panics(text in scene_like()) {
        check(&text, &[])?;
    }

    #[test]
    fn mutated_fig1_never_panics(edits in prop::collection::vec(edit(), 1..6)) {
        check(&mutate(FIG1, &edits), &[])?;
    }

    #[test]
    fn arbitrary_overrides_never_panic(sets in prop::collection::vec(assignment(), 0..4)) {
        check(FIG1, &sets)?;
    }
}

/// The unmutated scene is valid (so the mutations above start from a valid scene).
#[test]
fn fig1_text_is_valid() {
    check(FIG1, &[]).unwrap();
    assert!(Scene::from_toml_str(FIG1, "fuzz.toml", "fuzz", &[]).is_ok());
}

/// Inputs the properties above once failed on: a key or an assignment holding a line break
/// made a two-line error message; a subnormal mass left a stability limit NaN, which the
/// report's number formatting did not expect.
#[test]
fn regressions() {
    check("\"a\\nb\" = 0", &[]).unwrap();
    check("[junctions]\n\"x\\u2028y\" = 1", &[]).unwrap();
    check(FIG1, &["\r".to_string()]).unwrap();
    check(FIG1, &["plate.v=1\n2".to_string()]).unwrap();
    for m in ["1e-320", "5e-324", "1e-300"] {
        check(FIG1, &[format!("plate.mass={m}")]).unwrap();
    }
}
