//! `himal aa-patterns`: the A5 sampling-pattern study (CPU only).

use anyhow::{Result, bail};
use clap::Args;
use himal::passes::aa::patterns::{StudySettings, study};

#[derive(Args, Debug)]
pub struct AaPatternsArgs {
    /// Edge orientations over [0, π).
    #[arg(long, default_value_t = 720, allow_hyphen_values = true, value_parser = crate::whole_number)]
    pub angles: u32,
    /// Edge offsets per orientation.
    #[arg(long, default_value_t = 400, allow_hyphen_values = true, value_parser = crate::whole_number)]
    pub offsets: u32,
    /// Width of the 1024-sample reference box in pixels.
    #[arg(long, default_value_t = 1.25, allow_hyphen_values = true)]
    pub reference_width: f64,
    /// Exponent p of the orientation weight cos(2θ)^p (even).
    #[arg(long, default_value_t = 16)]
    pub orientation_exponent: i32,
}

pub fn run(args: &AaPatternsArgs) -> Result<()> {
    if args.angles == 0 || args.offsets == 0 {
        bail!("--angles and --offsets must be at least 1");
    }
    if !(args.reference_width >= 1.0 && args.reference_width <= 2.0) {
        bail!(
            "--reference-width {} is outside [1, 2] pixels",
            args.reference_width
        );
    }
    if args.orientation_exponent < 0 || args.orientation_exponent % 2 != 0 {
        bail!(
            "--orientation-exponent {} must be even and not negative",
            args.orientation_exponent
        );
    }
    let settings = StudySettings {
        angles: args.angles,
        offsets: args.offsets,
        reference_width: args.reference_width,
        orientation_exponent: args.orientation_exponent,
        ..StudySettings::default()
    };
    println!(
        "coverage error of box-filtered half-plane edges vs a 1024-sample reference \
         ({} orientations x {} offsets, reference box {} px, weight cos(2θ)^{})",
        settings.angles, settings.offsets, settings.reference_width, settings.orientation_exponent
    );
    println!(
        "{:<16} {:>8} {:>8} {:>8} {:>8}",
        "pattern", "samples", "rms", "E", "E talk"
    );
    for r in study(settings) {
        let talk = match (r.name, r.talk) {
            ("1x centre", _) => ">1.0".to_string(),
            (_, Some(t)) => format!("{t:.3}"),
            (_, None) => "-".to_string(),
        };
        println!(
            "{:<16} {:>8} {:>8.4} {:>8.3} {:>8}",
            r.name, r.cost, r.rms, r.e, talk
        );
    }
    Ok(())
}
