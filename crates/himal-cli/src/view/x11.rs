//! The X11 libraries the viewer loads at run time, checked before winit
//! opens a window.

use anyhow::{Result, bail};

/// The X11 libraries winit opens at run time, with their Debian/Ubuntu
/// packages: without them winit panics or reports a display failure.
const X11_LIBRARIES: [(&str, &str); 7] = [
    ("libX11.so.6", "libx11-6"),
    ("libX11-xcb.so.1", "libx11-xcb1"),
    ("libxkbcommon.so.0", "libxkbcommon0"),
    ("libxkbcommon-x11.so.0", "libxkbcommon-x11-0"),
    ("libXi.so.6", "libxi6"),
    ("libXcursor.so.1", "libxcursor1"),
    ("libXrandr.so.2", "libxrandr2"),
];

/// Fails naming every missing library (and its package) that `opens`
/// cannot load.
pub(super) fn check_x11_libraries(opens: impl Fn(&str) -> bool) -> Result<()> {
    let missing: Vec<_> = X11_LIBRARIES
        .iter()
        .filter(|(lib, _)| !opens(lib))
        .collect();
    if missing.is_empty() {
        return Ok(());
    }
    let libs: Vec<&str> = missing.iter().map(|(l, _)| *l).collect();
    let packages: Vec<&str> = missing.iter().map(|(_, p)| *p).collect();
    bail!(
        "himal view cannot load the X11 libraries {} (Debian/Ubuntu packages: {}; `./run view` installs them)",
        libs.join(", "),
        packages.join(" ")
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn missing_x11_libraries_are_named_with_their_packages() {
        assert!(check_x11_libraries(|_| true).is_ok());
        let e = check_x11_libraries(|l| !l.starts_with("libxkbcommon-x11") && l != "libXi.so.6")
            .unwrap_err()
            .to_string();
        assert!(e.contains("libxkbcommon-x11.so.0, libXi.so.6"), "{e}");
        assert!(e.contains("libxkbcommon-x11-0 libxi6"), "{e}");
        assert!(!e.contains("display"), "{e}");
    }
}
