//! `anholonomy` command-line interface: parse (`cmd::cli`), dispatch to
//! the command's module in `cmd/`, print errors one per line.

use anholonomy::error::ErrorKind;
use clap::Parser;
use cmd::cli::{Cli, Cmd, ModelsCmd};
use cmd::run::Mode;
use std::process::ExitCode;

/// `println!` for command output that ignores a closed stdout (`| head`)
/// instead of panicking.
macro_rules! say {
    ($($t:tt)*) => {{
        use std::io::Write as _;
        let _ = writeln!(std::io::stdout().lock(), $($t)*);
    }};
}

/// Print text to stdout, ignoring a closed stdout (`| head`) like `say!`.
fn emit(text: &str) {
    use std::io::Write as _;
    let _ = write!(std::io::stdout().lock(), "{text}");
}

mod cmd;

/// A command-line error as one line (exit 2, like every bad input): clap's
/// own first line, with its tip (a similar argument, `--` before a value)
/// in parentheses, without the usage block. Help and version are printed
/// as clap prints them.
fn one_line(e: &clap::Error) -> String {
    let text = e.render().to_string();
    let mut lines = text.lines().map(str::trim).filter(|l| !l.is_empty());
    let first = lines.next().unwrap_or("error: bad arguments");
    let first = first.strip_prefix("error: ").unwrap_or(first);
    let tips: Vec<&str> = lines.filter_map(|l| l.strip_prefix("tip: ")).collect();
    if tips.is_empty() {
        first.to_string()
    } else {
        format!("{first} (tip: {})", tips.join("; "))
    }
}

fn main() -> ExitCode {
    // External laws run in process groups of their own: Ctrl-C reaches
    // them through the harness.
    #[cfg(unix)]
    anholonomy::sources::external::process::on_signal::install();
    let cli = match Cli::try_parse() {
        Ok(c) => c,
        Err(e) if !e.use_stderr() => e.exit(),
        Err(e) => {
            eprintln!("error: {}", one_line(&e));
            return ExitCode::from(2);
        }
    };
    let res = match &cli.cmd {
        Cmd::Run(a) => cmd::run::run_cmd(a, Mode::Run),
        Cmd::Check(a) => cmd::run::run_cmd(a, Mode::Check),
        Cmd::Baseline(a) => cmd::run::run_cmd(a, Mode::WriteBaselines),
        Cmd::Report { logdir } => cmd::logs::report_cmd(logdir),
        Cmd::Plan {
            file,
            json,
            max_steps,
        } => cmd::inspect::plan_cmd(file, *json, *max_steps),
        Cmd::List { paths, max_steps } => cmd::inspect::list_cmd(paths, *max_steps),
        Cmd::Keys {
            name,
            markdown,
            out,
        } => cmd::inspect::keys_cmd(name.as_deref(), *markdown, out.as_deref()),
        Cmd::Merge { paths, out } => cmd::logs::merge_cmd(paths, out.as_deref()),
        Cmd::Margin(a) => cmd::margin::margin_cmd(a),
        Cmd::Fit(a) => cmd::fit::fit_cmd(a),
        Cmd::Init(a) => cmd::inspect::init_cmd(&a.dir, a.from.as_deref()),
        Cmd::Models(a) => match &a.cmd {
            None => cmd::inspect::models_cmd(),
            Some(ModelsCmd::Export { dir, names, force }) => {
                cmd::inspect::export_cmd(dir, names, *force)
            }
        },
    };
    match res {
        Ok(code) => ExitCode::from(code),
        Err(errors) => {
            for e in &errors {
                // A last guard for numbers a message writes in full (1e300 as
                // 301 digits): the messages format theirs readably already.
                eprintln!(
                    "error: {}",
                    anholonomy::numfmt::shorten_long_numbers(&e.to_string())
                );
            }
            // 2: bad input; 3: a failure at run time.
            let runtime = errors.iter().any(|e| e.kind() == ErrorKind::Runtime);
            ExitCode::from(if runtime { 3 } else { 2 })
        }
    }
}
