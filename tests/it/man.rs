//! The manual and the shell completions, generated from the clap definitions: `trajdrift man` (to
//! stdout, or one page per command with `--out DIR`) and `trajdrift completions SHELL` name every
//! command, and every command's `--help` ends with real examples.

use std::process::{Command, Output};

fn run(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_trajdrift"))
        .args(args)
        .output()
        .expect("run trajdrift")
}

fn stdout(o: &Output) -> String {
    assert!(
        o.status.success(),
        "exit {:?}: {}",
        o.status.code(),
        String::from_utf8_lossy(&o.stderr)
    );
    String::from_utf8_lossy(&o.stdout).into_owned()
}

/// The commands `trajdrift --help` lists (its `Commands:` section), `help` left out.
fn commands() -> Vec<String> {
    let help = stdout(&run(&["--help"]));
    let names: Vec<String> = help
        .lines()
        .skip_while(|l| !l.starts_with("Commands:"))
        .skip(1)
        .take_while(|l| l.starts_with("  "))
        .filter_map(|l| l.split_whitespace().next())
        .filter(|n| *n != "help")
        .map(str::to_string)
        .collect();
    for known in [
        "eval",
        "topics",
        "simulate",
        "batch",
        "merge",
        "export",
        "sweep",
        "ape",
        "rpe",
        "offset",
        "man",
        "completions",
        "audit",
        "restamp",
    ] {
        assert!(names.iter().any(|n| n == known), "{known} not in {names:?}");
    }
    names
}

#[test]
fn man_page_lists_every_command_with_examples() {
    let page = stdout(&run(&["man"]));
    assert!(page.contains(".TH trajdrift 1"), "{page}");
    for section in [
        "NAME",
        "SYNOPSIS",
        "SUBCOMMANDS",
        "EXAMPLES",
        "\"EXIT STATUS\"",
    ] {
        assert!(
            page.contains(&format!(".SH {section}")),
            "{section}: {page}"
        );
    }
    for c in commands() {
        assert!(page.contains(&format!("trajdrift\\-{c}(1)")), "{c}: {page}");
    }
}

#[test]
fn man_out_writes_one_page_per_command() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("man1");
    let listed = stdout(&run(&["man", "--out", out.to_str().unwrap()]));
    let main = std::fs::read_to_string(out.join("trajdrift.1")).unwrap();
    assert_eq!(main, stdout(&run(&["man"])));
    for c in commands() {
        let path = out.join(format!("trajdrift-{c}.1"));
        assert!(listed.contains(&*path.to_string_lossy()), "{c}: {listed}");
        let page = std::fs::read_to_string(&path).unwrap();
        assert!(
            page.contains(&format!(".TH trajdrift-{c} 1")),
            "{c}: {page}"
        );
        assert!(page.contains(".SH EXAMPLES"), "{c}: {page}");
        assert!(page.contains(&format!("trajdrift {c} ")), "{c}: {page}");
    }
    // Nothing else, and no temporary file left behind.
    let n = std::fs::read_dir(&out).unwrap().count();
    assert_eq!(n, commands().len() + 1);
}

#[test]
fn bash_completions_name_every_command_and_load() {
    let script = stdout(&run(&["completions", "bash"]));
    for c in commands() {
        assert!(
            script
                .split(|ch: char| !ch.is_alphanumeric() && ch != '-' && ch != '_')
                .any(|w| w == c),
            "{c} not in the bash completions"
        );
    }
    // bash reads it and registers the completion (where bash is installed).
    let dir = tempfile::tempdir().unwrap();
    let file = dir.path().join("trajdrift.bash");
    std::fs::write(&file, &script).unwrap();
    if let Ok(o) = Command::new("bash")
        .arg("-c")
        .arg(format!(
            "source '{}' && complete -p trajdrift",
            file.display()
        ))
        .output()
    {
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        assert!(String::from_utf8_lossy(&o.stdout).contains("trajdrift"));
    }
}

#[test]
fn completions_for_every_shell() {
    for shell in ["bash", "zsh", "fish", "elvish", "powershell"] {
        let script = stdout(&run(&["completions", shell]));
        assert!(script.contains("trajdrift"), "{shell}");
        assert!(script.contains("completions"), "{shell}");
    }
    let o = run(&["completions", "tcsh"]);
    assert_eq!(o.status.code(), Some(2));
}

#[test]
fn every_command_help_ends_with_examples() {
    for c in commands() {
        let help = stdout(&run(&[&c, "--help"]));
        let examples = help
            .split("Examples:")
            .nth(1)
            .unwrap_or_else(|| panic!("{c} --help has no examples: {help}"));
        let lines = examples
            .lines()
            .filter(|l| l.trim_start().starts_with(&format!("trajdrift {c} ")))
            .count();
        assert!(lines >= 2, "{c}: {lines} examples");
    }
}
