//! `raypath completions <shell>` and `raypath man`: shell completions and man pages generated
//! from the command line definition itself, so they never fall behind it.

use std::path::PathBuf;

use clap_complete::Shell;

use super::Failure;

/// Arguments of `raypath completions`.
#[derive(clap::Args, Debug)]
pub struct CompletionsArgs {
    /// The shell: bash, zsh, fish, elvish or powershell.
    #[arg(value_enum)]
    pub shell: Shell,
}

/// Arguments of `raypath man`.
#[derive(clap::Args, Debug)]
pub struct ManArgs {
    /// Write `raypath.1` and one `raypath-<command>.1` per subcommand into this directory
    /// (created if missing); without it, the top-level page goes to standard output.
    #[arg(long, value_name = "DIR")]
    pub out: Option<PathBuf>,
}

/// Writes the completion script for `args.shell` to standard output.
pub fn completions(args: &CompletionsArgs, mut command: clap::Command) -> Result<(), Failure> {
    let name = command.get_name().to_owned();
    clap_complete::generate(args.shell, &mut command, name, &mut std::io::stdout());
    Ok(())
}

/// Writes the man pages.
pub fn man(args: &ManArgs, command: clap::Command) -> Result<(), Failure> {
    let Some(dir) = &args.out else {
        return clap_mangen::Man::new(command)
            .render(&mut std::io::stdout())
            .map_err(|e| Failure::input(format!("standard output: {e}")));
    };
    std::fs::create_dir_all(dir).map_err(|e| Failure::input(format!("{}: {e}", dir.display())))?;
    clap_mangen::generate_to(command, dir)
        .map_err(|e| Failure::input(format!("{}: {e}", dir.display())))?;
    println!("man pages written to {}", dir.display());
    Ok(())
}
