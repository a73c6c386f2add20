use asperity::{Error, Result};

#[derive(clap::Subcommand)]
pub enum SurfaceCommand {
    /// Gaussian-correlated rough patch from profilometer statistics.
    Generate,
}

pub fn run(_cmd: SurfaceCommand) -> Result<()> {
    Err(Error::Data("`surface` is not implemented yet".into()))
}
