use asperity::{Error, Result};

#[derive(clap::Args)]
pub struct TangentialArgs {}

pub fn run(_args: TangentialArgs) -> Result<()> {
    Err(Error::Data(
        "`contact contact_tangential` is not implemented yet".into(),
    ))
}
