//! What a file is, from its first bytes: the format is chosen by content, and the suffix
//! only has to agree. Formats that are recognised but not read are named, with who reads
//! them, so that a user knows what to convert.

/// What the first bytes of a file say it is.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Content {
    Npy,
    /// A zip archive: an X3P file if it holds a `main.xml`.
    Zip,
    NetCdf3,
    Gsf,
    SdfText,
    SdfBinary,
    /// Text: a matrix, an x-y-z list or a line scan, told apart by its numbers.
    Text,
    /// Recognised, not read: what it is and who reads it.
    Foreign(&'static str),
    /// Binary, of no format known here.
    Binary,
}

/// The content of a file whose first bytes (up to 64 KiB) are `head`.
pub fn sniff(head: &[u8]) -> Content {
    let starts = |m: &[u8]| head.starts_with(m);
    if starts(b"\x93NUMPY") {
        Content::Npy
    } else if starts(b"PK\x03\x04") || starts(b"PK\x05\x06") {
        Content::Zip
    } else if starts(b"CDF\x01") || starts(b"CDF\x02") || starts(b"CDF\x05") {
        Content::NetCdf3
    } else if starts(b"Gwyddion Simple Field") {
        Content::Gsf
    } else if starts(b"aISO-1.0") {
        Content::SdfText
    } else if starts(b"bISO-1.0") {
        Content::SdfBinary
    } else if starts(b"\xef\xbf\xbdNUMPY") {
        Content::Foreign("a .npy file corrupted by a text conversion (its first byte, 0x93, became U+FFFD): save the array again with numpy.save, or copy it as binary")
    } else if starts(b"\x89HDF\r\n\x1a\n") {
        Content::Foreign("NetCDF 4 / HDF5: not read here; save it as NetCDF 3 (SurfaceTopography's `to_netcdf(..., format='NETCDF3_64BIT_OFFSET')`) or X3P")
    } else if matches!(head.get(..4), Some([0x88, 0x1b, 0x03, 0x6f..=0x71])) {
        Content::Foreign("Zygo MetroPro (.dat): not read here; SurfaceTopography reads it (`read_topography`), then `to_netcdf` or X3P")
    } else if starts(b"GWYP") || starts(b"GWYO") {
        Content::Foreign("a Gwyddion native file (.gwy): not read here; export the channel as .gsf or X3P from Gwyddion")
    } else if starts(b"II*\0") || starts(b"MM\0*") {
        Content::Foreign("a TIFF image: not read here (its heights have no stated unit); export the map as X3P, SDF or a text matrix")
    } else if starts(b"\x89PNG") || starts(b"\xff\xd8\xff") {
        Content::Foreign("an image (PNG or JPEG): an image's grey levels are not heights; export the map as X3P, SDF or a text matrix")
    } else if starts(b"DIGITAL SURF") {
        Content::Foreign("a Digital Surf file (.sur): not read here; SurfaceTopography or Gwyddion read it, then save it as X3P or NetCDF")
    } else if starts(b"\\*File list") {
        Content::Foreign(
            "a Bruker Nanoscope file: not read here; SurfaceTopography or Gwyddion read it",
        )
    } else if starts(b"OPD") || starts(b"\x01\x00OPD") {
        Content::Foreign("a Veeco/Wyko OPD file: not read here; SurfaceTopography reads it")
    } else if starts(b"\xff\xfe") || starts(b"\xfe\xff") {
        // A UTF-16 byte-order mark: text as Windows software exports it.
        Content::Text
    } else if is_text(head) {
        Content::Text
    } else {
        Content::Binary
    }
}

/// No NUL byte and few control characters: text (UTF-8 or Latin-1).
fn is_text(head: &[u8]) -> bool {
    let head = head.strip_prefix(b"\xef\xbb\xbf").unwrap_or(head);
    !head.contains(&0)
        && head
            .iter()
            .filter(|&&b| b < 0x20 && !matches!(b, b'\n' | b'\r' | b'\t' | 0x0c))
            .count()
            * 20
            <= head.len()
}

/// The suffixes each content goes by, for the check that a suffix agrees with the content.
pub fn suffixes(content: Content) -> &'static [&'static str] {
    match content {
        Content::Npy => &["npy"],
        Content::Zip => &["x3p"],
        Content::NetCdf3 => &["nc"],
        Content::Gsf => &["gsf"],
        Content::SdfText | Content::SdfBinary => &["sdf"],
        Content::Text => &["txt", "csv", "asc", "dat", "xyz", "tsv"],
        Content::Foreign(_) | Content::Binary => &[],
    }
}

/// The content in words.
pub fn name(content: Content) -> &'static str {
    match content {
        Content::Npy => "a numpy .npy array",
        Content::Zip => "a zip archive (X3P)",
        Content::NetCdf3 => "a NetCDF 3 file",
        Content::Gsf => "a Gwyddion Simple Field",
        Content::SdfText => "a text SDF (ISO 25178-71)",
        Content::SdfBinary => "a binary SDF (ISO 25178-71)",
        Content::Text => "text",
        Content::Foreign(what) => what,
        Content::Binary => "a binary file of no format read here",
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn formats_by_their_first_bytes() {
        assert_eq!(sniff(b"\x93NUMPY\x01\x00"), Content::Npy);
        assert_eq!(sniff(b"PK\x03\x04rest"), Content::Zip);
        assert_eq!(sniff(b"CDF\x02\0\0"), Content::NetCdf3);
        assert_eq!(sniff(b"aISO-1.0\nManufacID"), Content::SdfText);
        assert_eq!(sniff(b"1 2 3\n4 5 6\n"), Content::Text);
        assert_eq!(sniff(b"\xef\xbb\xbf1 2\n"), Content::Text);
        assert_eq!(sniff(b"\xff\xfe1\x00 \x002\x00"), Content::Text);
        assert!(
            matches!(sniff(b"\x88\x1b\x03\x6f\0\0\0\0"), Content::Foreign(w) if w.contains("MetroPro"))
        );
        assert!(matches!(sniff(b"\x89HDF\r\n\x1a\n"), Content::Foreign(w) if w.contains("HDF5")));
        assert_eq!(sniff(b"\x01\x02\x03\0\0\0\x07"), Content::Binary);
    }
}
