use asperity::{Error, Result};

#[derive(clap::Args)]
pub struct NormalArgs {}

pub fn run(_args: NormalArgs) -> Result<()> {
    Err(Error::Data(
        "`contact contact_normal` is not implemented yet".into(),
    ))
}
