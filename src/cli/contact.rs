use asperity::Result;

#[derive(clap::Subcommand)]
pub enum ContactCommand {
    /// Normal contact pressure sweep: area ratio, mean gap and kn versus nominal pressure.
    Normal(super::contact_normal::NormalArgs),
    /// Tangential hysteresis loops under oscillating displacement, one per pressure.
    Tangential(super::contact_tangential::TangentialArgs),
}

pub fn run(cmd: ContactCommand) -> Result<()> {
    match cmd {
        ContactCommand::Normal(a) => super::contact_normal::run(a),
        ContactCommand::Tangential(a) => super::contact_tangential::run(a),
    }
}
