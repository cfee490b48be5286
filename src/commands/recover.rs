//! `slipfront recover`: a cut-short run file rewritten whole.

use slipfront::io::output::lock::RunLock;
use slipfront::io::output::recover::rewrite;
use slipfront::io::output::scan::Ending;
use std::path::{Path, PathBuf};
use std::process::ExitCode;

pub fn recover(file: &Path, out: Option<PathBuf>, force: bool) -> anyhow::Result<ExitCode> {
    anyhow::ensure!(file.is_file(), "{}: no such run file", file.display());
    let in_place = out.is_none();
    let target = out.unwrap_or_else(|| file.to_path_buf());
    let backup = with_suffix(file, ".cut");
    if in_place {
        anyhow::ensure!(
            force || !backup.exists(),
            "`{}` exists (an earlier recovery's copy of the cut file); move it away or pass \
             --force",
            backup.display()
        );
    } else {
        anyhow::ensure!(
            target.canonicalize().ok() != file.canonicalize().ok() || !target.exists(),
            "-o {}: that is the input; leave -o out to recover in place",
            target.display()
        );
        anyhow::ensure!(
            force || !target.exists(),
            "`{}` exists; replace it with --force",
            target.display()
        );
    }
    // Neither the file nor its target may be written by a run meanwhile.
    let _locks = [Some(file), (!in_place).then_some(target.as_path())]
        .into_iter()
        .flatten()
        .map(|p| RunLock::acquire(p, "recover").map_err(anyhow::Error::msg))
        .collect::<anyhow::Result<Vec<_>>>()?;
    let partial = with_suffix(&target, ".recovering");
    let report = match rewrite(file, &partial) {
        Ok(r) => r,
        Err(e) => {
            let _ = std::fs::remove_file(&partial);
            return Err(e.into());
        }
    };
    if report.ending == Ending::Complete && in_place {
        std::fs::remove_file(&partial)?;
        println!(
            "{} is complete ({} messages, summary and footer present): nothing to do",
            file.display(),
            report.messages
        );
        return Ok(ExitCode::SUCCESS);
    }
    if in_place {
        std::fs::rename(file, &backup)?;
    }
    std::fs::rename(&partial, &target)?;
    let how = match &report.ending {
        Ending::Complete => "was complete".to_string(),
        Ending::CutShort => "ended before its summary".to_string(),
        Ending::Damaged(why) => format!("was damaged ({why})"),
    };
    println!(
        "{} {how}: {} messages kept, up to t = {}; written whole to {}{}",
        file.display(),
        report.messages,
        report
            .last_time
            .map_or("(none)".to_string(), |t| format!("{t:.6e} s")),
        target.display(),
        if in_place {
            format!(" (the cut file kept as {})", backup.display())
        } else {
            String::new()
        }
    );
    Ok(ExitCode::SUCCESS)
}

fn with_suffix(path: &Path, suffix: &str) -> PathBuf {
    let mut s = path.as_os_str().to_owned();
    s.push(suffix);
    PathBuf::from(s)
}
