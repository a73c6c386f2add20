use asperity::{Error, Result};

#[derive(clap::Args)]
pub struct DiagnoseArgs {}

pub fn run(_args: DiagnoseArgs) -> Result<()> {
    Err(Error::Data("`diagnose` is not implemented yet".into()))
}
