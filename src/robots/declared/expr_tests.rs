//! Tests of `expr.rs`.

use super::*;

fn err(text: &str) -> String {
    Expr::parse(text, &["x", "v"]).unwrap_err().to_string()
}

#[test]
fn malformed_expressions_are_one_line_not_a_panic() {
    for t in [
        "v *", "* v", "-", "v +", "sin()", "atan2(x)", "()", "(v", "v)",
    ] {
        let e = err(t);
        assert!(!e.contains('\n'), "{t}: {e}");
    }
    assert!(err("v *").contains("`*` needs an operand on each side"));
    let e = err("\"a\nb\"");
    assert!(e.contains("is not a number") && !e.contains('\n'), "{e}");
}

#[test]
fn limits_are_named_and_hold_without_recursion() {
    let sum = vec!["x"; 25_000].join("+");
    assert_eq!(
        err(&sum),
        "the expression has 49999 characters, over the limit of 4096"
    );
    let e = err(&format!("{}x", "-".repeat(50_000)));
    assert!(e.contains("over the limit of 4096"), "{e}");
    let e = err(&format!("{}x", "-".repeat(100)));
    assert!(e.contains("levels of nesting"), "{e}");
    assert!(e.contains("(101 characters)"), "{e}");
    let e = err(&format!("{}x{}", "(".repeat(70), ")".repeat(70)));
    assert!(e.contains("over the limit of 64"), "{e}");
    let e = err(&vec!["x"; 70].join("^"));
    assert!(e.contains("over the limit of 64"), "{e}");
    // A long sum within the limit: a tree 2048 levels deep, compiled and
    // taken apart without recursion; its stack stays 2 deep.
    let sum = vec!["x"; 2048].join("+");
    let e = Expr::parse(&sum, &["x"]).unwrap();
    assert_eq!(e.eval(&[0.5]), 1024.0);
    assert_eq!(e.stack_depth(), 2);
    // Nesting within the limit parses.
    let t = format!("{}x{}", "(".repeat(30), ")".repeat(30));
    assert_eq!(Expr::parse(&t, &["x"]).unwrap().eval(&[2.0]), 2.0);
    assert_eq!(Expr::parse("- - -x", &["x"]).unwrap().eval(&[2.0]), -2.0);
}

/// Deep text: `n` wrappers drawn from signs, parentheses, calls and
/// powers around `x`, closed (or not) at the end.
fn nested(kinds: &[u8], close: bool) -> String {
    let (mut open, mut shut) = (String::new(), String::new());
    for k in kinds {
        let (o, c) = match k % 6 {
            0 => ("-", ""),
            1 => ("(", ")"),
            2 => ("sin(", ")"),
            3 => ("x^", ""),
            4 => ("+", ""),
            _ => ("atan2(x, ", ")"),
        };
        open.push_str(o);
        shut.insert_str(0, c);
    }
    if close {
        format!("{open}x{shut}")
    } else {
        format!("{open}x")
    }
}

/// Parse and compile one text: `Ok`, or an error of one short line.
fn one_line_or_ok(text: &str) -> Result<(), String> {
    match Expr::parse(text, &["x", "v", "theta"]) {
        Ok(e) => {
            e.eval(&[0.3, -0.2, 1.1]);
            Ok(())
        }
        Err(e) => {
            let m = e.to_string();
            if m.contains('\n') || m.chars().count() > 1200 {
                Err(format!("not one short line ({} characters): {m}", m.len()))
            } else {
                Ok(())
            }
        }
    }
}

/// The property, on a thread with a quarter of a spawned thread's
/// default stack: arbitrary text, deep nesting and long sums.
fn property() {
    use proptest::prelude::*;
    use proptest::test_runner::{TestCaseError, TestRunner};
    let check = |t: &str| one_line_or_ok(t).map_err(TestCaseError::fail);
    // A runner per strategy: one counts its cases across `run`s.
    let runner = || {
        TestRunner::new(proptest::test_runner::Config {
            failure_persistence: None,
            ..crate::prop_config::config(256)
        })
    };
    runner().run(&any::<String>(), |t| check(&t)).unwrap();
    runner()
        .run(&"[-+*/^(), .0-9a-z_\"=<>!&|;%]{0,400}", |t| check(&t))
        .unwrap();
    let deep = (prop::collection::vec(any::<u8>(), 0..3000), any::<bool>());
    runner()
        .run(&deep, |(kinds, close)| check(&nested(&kinds, close)))
        .unwrap();
    // Runs of signs (`- - - x`: evalexpr recurses once per sign).
    runner()
        .run(&(0..60_000usize, any::<bool>()), |(n, spaced)| {
            let sign = if spaced { "- " } else { "-" };
            check(&format!("{}x", sign.repeat(n)))
        })
        .unwrap();
    // Sums within the length limit (trees up to 2048 deep) and beyond it.
    for terms in [1..2048usize, 2048..30_000] {
        let ops = prop::collection::vec(prop::sample::select(vec!["+", "-", "*", "/"]), terms);
        let junk = prop::sample::select(vec!["", ")", "(", "*", ",", " x"]);
        runner()
            .run(&(ops, junk), |(ops, junk)| {
                let mut t = String::from("x");
                for o in ops {
                    t.push_str(o);
                    t.push('x');
                }
                t.push_str(junk);
                check(&t)
            })
            .unwrap();
    }
}

/// Parsing and compiling never panics and never overflows the stack:
/// the property runs in a child process (this test binary again), so a
/// stack overflow there (which aborts a whole process) fails this test
/// instead of killing the test binary; in the child it runs on a
/// 512 KiB stack, a quarter of a spawned thread's default.
#[test]
fn parsing_any_text_is_ok_or_one_line_never_a_crash() {
    const CHILD: &str = "ANHOLONOMY_EXPR_PROPERTY_CHILD";
    // This test's path below the crate (it moves with the module).
    let name = format!(
        "{}::parsing_any_text_is_ok_or_one_line_never_a_crash",
        module_path!().trim_start_matches("anholonomy::")
    );
    if std::env::var_os(CHILD).is_some() {
        let t = std::thread::Builder::new()
            .stack_size(512 * 1024)
            .spawn(property)
            .unwrap();
        if let Err(e) = t.join() {
            std::panic::resume_unwind(e);
        }
        return;
    }
    let dir = tempfile::tempdir().unwrap();
    let (so, se) = (dir.path().join("out"), dir.path().join("err"));
    let mut child = std::process::Command::new(std::env::current_exe().unwrap())
        .args([name.as_str(), "--exact", "--nocapture", "--test-threads=1"])
        .env(CHILD, "1")
        .stdout(std::fs::File::create(&so).unwrap())
        .stderr(std::fs::File::create(&se).unwrap())
        .spawn()
        .unwrap();
    // A hang guard, not a timing claim: the property takes well under a
    // second; a parser that takes quadratic time again takes hours.
    let t0 = std::time::Instant::now();
    let status = loop {
        if let Some(s) = child.try_wait().unwrap() {
            break Some(s);
        }
        if t0.elapsed() > std::time::Duration::from_secs(300) {
            let _ = child.kill();
            let _ = child.wait();
            break None;
        }
        std::thread::sleep(std::time::Duration::from_millis(20));
    };
    let stdout = std::fs::read_to_string(&so).unwrap_or_default();
    let stderr = std::fs::read_to_string(&se).unwrap_or_default();
    assert!(
        status.is_some_and(|s| s.success()),
        "the property's process ended with {status:?} (None: killed after 300 s):\n{stdout}\n{stderr}"
    );
    assert!(
        stdout.contains("1 passed"),
        "the property did not run: {stdout}"
    );
}

#[test]
fn nesting_counts_signs_powers_and_parentheses() {
    assert_eq!(nesting("x", 64), 1);
    assert_eq!(nesting("a - b - c", 64), 1);
    assert_eq!(nesting("-x", 64), 2);
    assert_eq!(nesting("- - x", 64), 3);
    assert_eq!(nesting("a^b^c", 64), 3);
    assert_eq!(nesting("a^2 + b^2", 64), 2);
    assert_eq!(nesting("(x)", 64), 3);
    assert_eq!(nesting("sin(cos(x))", 64), 5);
    assert_eq!(nesting("1e-5 * x", 64), 1);
}
