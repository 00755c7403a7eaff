//! `caustic compare`: relative errors of an image against a reference, as JSON.

use std::path::Path;

use caustic::desktop::cli::CompareArgs;
use caustic::desktop::image::{compare, mask_above, Image, ImageError};
use serde::Serialize;

use crate::{bad_input, Failure};

/// What `compare` prints: the errors over the whole image, and inside the mask when
/// one is given (`null` when the mask selects no pixel). Non-finite ratios (a black
/// reference) are `null`.
#[derive(Serialize)]
struct Report {
    #[serde(flatten)]
    full: ImageError,
    #[serde(skip_serializing_if = "Option::is_none")]
    mask: Option<Option<ImageError>>,
}

/// Reads a PFM or OpenEXR image, binned; the error names the file.
fn read(path: &Path, bin: u32) -> Result<Image, Failure> {
    Image::read(path)
        .map(|i| i.binned(bin))
        .map_err(|e| bad_input(e.to_string()))
}

pub fn run(args: &CompareArgs) -> Result<(), Failure> {
    let a = read(&args.image, args.bin)?;
    let b = read(&args.reference, args.bin)?;
    if (a.width, a.height) != (b.width, b.height) {
        return Err(bad_input(format!(
            "sizes differ: {} is {}×{}, {} is {}×{}",
            args.image.display(),
            a.width,
            a.height,
            args.reference.display(),
            b.width,
            b.height
        )));
    }
    let full = compare(&a, &b, None).ok_or_else(|| bad_input("empty images"))?;
    let mask = match &args.mask {
        None => None,
        Some(path) => {
            let m = read(path, args.bin)?;
            if (m.width, m.height) != (a.width, a.height) {
                return Err(bad_input(format!(
                    "{}: the mask's size differs from the images'",
                    path.display()
                )));
            }
            Some(compare(&a, &b, Some(&mask_above(&m, args.mask_fraction))))
        }
    };
    let json = serde_json::to_string(&Report { full, mask })
        .map_err(|e| bad_input(format!("cannot write JSON: {e}")))?;
    println!("{json}");
    Ok(())
}
