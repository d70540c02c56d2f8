//! Commands on written logs: `report` and `merge`.

use anholonomy::error::Error;
use std::path::{Path, PathBuf};
use std::time::Instant;

pub fn report_cmd(logdir: &Path) -> Result<u8, Vec<Error>> {
    let t0 = Instant::now();
    let w = anholonomy::report::write_report(logdir, None).map_err(|e| vec![e])?;
    say!(
        "report: {} ({} scenarios, {:.2} s)",
        anholonomy::echo::path(&logdir.join("index.html")),
        w.scenarios,
        t0.elapsed().as_secs_f64()
    );
    Ok(0)
}

pub fn merge_cmd(paths: &[PathBuf], out: Option<&Path>) -> Result<u8, Vec<Error>> {
    let (sum, path) = anholonomy::sweep::merge::merge(paths, out)?;
    crate::emit(&sum.table);
    say!("merged: {}", anholonomy::echo::path(&path));
    Ok(0)
}
