//! Numbers in text, as instruments and spreadsheets write them: one record per line,
//! separated by white space, tabs, commas or semicolons; a decimal comma where the fields
//! are separated by tabs, spaces or semicolons (`0,0403\t1,2`); a byte-order mark at the
//! start ignored; comment lines (`#`, `%`) and header lines before the first number kept
//! apart. What the table holds (a map, an x-y-z list, a line scan) is decided from the
//! numbers by [`classify`], never from the file's suffix.

/// A table of numbers read from text.
#[derive(Debug, Clone)]
pub struct Table {
    /// Lines before the first row of numbers and comment lines anywhere, trimmed.
    pub header: Vec<String>,
    /// Row-major, `rows × cols`.
    pub values: Vec<f64>,
    pub rows: usize,
    pub cols: usize,
    /// Whether the numbers were written with a decimal comma.
    pub decimal_comma: bool,
}

/// What a table of numbers is.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Shape {
    /// A matrix of heights, one row of the map per line.
    Matrix,
    /// One point per line, `x y z`, on a regular grid.
    Xyz,
    /// A profile: one column or row of heights, or `x z` pairs.
    LineScan,
}

/// The text of `bytes`: UTF-16 after its byte-order mark (as Windows instrument software
/// exports CSV), UTF-8 (a leading byte-order mark dropped) or, failing that, Latin-1 when
/// the bytes look like text; a binary file is refused.
pub fn decode(bytes: &[u8]) -> Result<String, String> {
    if let Some(text) = utf16(bytes) {
        return text;
    }
    let bytes = bytes.strip_prefix(b"\xef\xbb\xbf").unwrap_or(bytes);
    if looks_binary(bytes) {
        return Err(
            "is a binary file, not text (a matrix, an x-y-z list or a header of numbers)".into(),
        );
    }
    Ok(match std::str::from_utf8(bytes) {
        Ok(s) => s.to_string(),
        // Latin-1 (`µm` as 0xB5), as older instrument software writes it.
        Err(_) => bytes.iter().map(|&b| b as char).collect(),
    })
}

/// The text of `bytes` if they start with a UTF-16 byte-order mark (little- or big-endian).
fn utf16(bytes: &[u8]) -> Option<Result<String, String>> {
    let (rest, little) = if let Some(rest) = bytes.strip_prefix(b"\xff\xfe") {
        (rest, true)
    } else {
        (bytes.strip_prefix(b"\xfe\xff")?, false)
    };
    let units: Vec<u16> = rest
        .chunks_exact(2)
        .map(|c| {
            if little {
                u16::from_le_bytes([c[0], c[1]])
            } else {
                u16::from_be_bytes([c[0], c[1]])
            }
        })
        .collect();
    Some(
        String::from_utf16(&units)
            .map_err(|_| "starts as UTF-16 text but is not valid UTF-16".to_string())
            .and_then(|text| {
                if looks_binary(text.as_bytes()) {
                    Err("starts as UTF-16 text but holds binary data".into())
                } else {
                    Ok(text)
                }
            }),
    )
}

/// NUL bytes, or more than 5 % of control characters in the first 64 KiB: not text.
fn looks_binary(bytes: &[u8]) -> bool {
    let head = &bytes[..bytes.len().min(1 << 16)];
    if head.contains(&0) {
        return true;
    }
    let control = head
        .iter()
        .filter(|&&b| b < 0x20 && !matches!(b, b'\n' | b'\r' | b'\t' | 0x0c))
        .count();
    control * 20 > head.len()
}

/// Whether `field` is a number written with a decimal comma: digits, one comma between two
/// digits, no point (`0,0403`, `-1,5e-3`).
fn decimal_comma_field(field: &str) -> bool {
    let b = field.as_bytes();
    let commas: Vec<usize> = (0..b.len()).filter(|&i| b[i] == b',').collect();
    commas.len() == 1
        && !field.contains('.')
        && commas[0] > 0
        && b[commas[0] - 1].is_ascii_digit()
        && b.get(commas[0] + 1).is_some_and(u8::is_ascii_digit)
}

/// The fields of a line split on white space and semicolons (not commas).
fn wide_fields(line: &str) -> Vec<&str> {
    line.split(|c: char| c.is_whitespace() || c == ';')
        .filter(|f| !f.is_empty())
        .collect()
}

/// Parses a number as files write it; `nan` (any case) is a missing point.
fn number(token: &str) -> Option<f64> {
    token.trim().parse::<f64>().ok()
}

/// The numbers of one line, or the first field that is not one.
fn numbers(line: &str, decimal_comma: bool) -> Result<Vec<f64>, String> {
    let fields: Vec<String> = if decimal_comma {
        wide_fields(line)
            .iter()
            .map(|f| f.replace(',', "."))
            .collect()
    } else {
        line.split(|c: char| c.is_whitespace() || c == ',' || c == ';')
            .filter(|f| !f.is_empty())
            .map(String::from)
            .collect()
    };
    fields
        .iter()
        .map(|f| number(f).ok_or_else(|| f.clone()))
        .collect()
}

/// Read `text` into a table. Lines before the first line of numbers are the header; after
/// it, every line that is not blank or a comment must hold as many numbers as the first.
pub fn table(text: &str) -> Result<Table, String> {
    let mut header = Vec::new();
    let mut values = Vec::new();
    let (mut rows, mut cols) = (0usize, None::<usize>);
    let mut decimal_comma = None::<bool>;
    for (i, line) in text.lines().enumerate() {
        let line = line.trim();
        if line.is_empty() {
            continue;
        }
        if line.starts_with('#') || line.starts_with('%') {
            header.push(line.to_string());
            continue;
        }
        // The convention is set by the first line of numbers, and holds for the rest.
        let comma = *decimal_comma.get_or_insert_with(|| {
            let wide = wide_fields(line);
            let numeric = |f: &&str| number(&f.replace(',', ".")).is_some();
            wide.len() >= 2
                && wide.iter().all(numeric)
                && wide.iter().any(|f| decimal_comma_field(f))
                && wide
                    .iter()
                    .all(|f| !f.contains(',') || decimal_comma_field(f))
        });
        let v = match numbers(line, comma) {
            Ok(v) => v,
            Err(_) if cols.is_none() => {
                // A header line before the numbers (`h=650`, column names).
                decimal_comma = None;
                header.push(line.to_string());
                continue;
            }
            Err(token) => {
                let shown: String = token.chars().take(40).collect();
                return Err(format!("line {}: '{shown}' is not a number", i + 1));
            }
        };
        if let Some(x) = v.iter().find(|x| x.is_infinite()) {
            return Err(format!("line {}: '{x}' is not a height", i + 1));
        }
        match cols {
            None => cols = Some(v.len()),
            Some(c) if c != v.len() => {
                return Err(format!(
                    "line {} has {} values where the rows before have {c}: not a table",
                    i + 1,
                    v.len()
                ))
            }
            _ => {}
        }
        values.extend_from_slice(&v);
        rows += 1;
    }
    match cols {
        Some(c) if c > 0 => Ok(Table {
            header,
            values,
            rows,
            cols: c,
            decimal_comma: decimal_comma.unwrap_or(false),
        }),
        _ => Err("holds no heights (no line of numbers)".into()),
    }
}

/// Positions within this fraction of a pixel of their grid node are on the grid (text
/// written with 6 significant digits places a point of a 1000-pixel grid within 1e-3).
pub const GRID_TOLERANCE_PX: f64 = 0.01;

/// What a table is. Three columns whose first two take few values, about one grid node per
/// row, are an x-y-z list (whose grid [`super::xyz`] then checks); one row, one column, two
/// columns, or three whose first only increases (an index or x) are a profile; anything else
/// with at least two rows and three columns is a matrix.
pub fn classify(t: &Table) -> Shape {
    if t.rows == 1 || t.cols <= 2 {
        return Shape::LineScan;
    }
    if t.cols == 3 && t.rows >= 4 {
        let distinct = |k: usize| {
            let mut v: Vec<f64> = (0..t.rows).map(|r| t.values[r * 3 + k]).collect();
            v.sort_by(f64::total_cmp);
            v.dedup();
            v.len()
        };
        // A grid has about as many nodes as points (a few more where points are missing or
        // off the grid); three columns of heights have about as many distinct values as rows.
        let (nx, ny) = (distinct(0), distinct(1));
        if nx >= 2 && ny >= 2 && nx.saturating_mul(ny) <= 2 * t.rows {
            return Shape::Xyz;
        }
        // A first column that only increases (an index, or x) and no grid: a profile
        // written with an index column (`index, x, z`, as Windows CSV exports are).
        if (1..t.rows).all(|r| t.values[r * 3] > t.values[(r - 1) * 3]) {
            return Shape::LineScan;
        }
    }
    Shape::Matrix
}

/// What a line scan is, in words for an error message.
pub fn describe_line_scan(t: &Table) -> String {
    match (t.rows, t.cols) {
        (1, c) => format!("a line scan: one row of {c} heights"),
        (r, 1) => format!("a line scan: one column of {r} heights"),
        (r, 2) => format!("a line scan (x, z): {r} points of two columns"),
        (r, _) => format!(
            "a line scan (an increasing first column, an index or x, then two): {r} points of three columns"
        ),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn decimal_commas_with_tabs_spaces_and_semicolons() {
        for text in [
            "0,0403\t1,5\t-2,25e-1\n1\t2\t3\n",
            "0,0403 1,5 -2,25e-1\n1 2 3\n",
            "0,0403;1,5;-2,25e-1\n1;2;3\n",
        ] {
            let t = table(text).unwrap();
            assert!(t.decimal_comma, "{text:?}");
            assert_eq!((t.rows, t.cols), (2, 3));
            assert_eq!(&t.values[..3], &[0.0403, 1.5, -0.225]);
        }
        // Commas that separate fields stay separators.
        for text in [
            "1.5,2.5,3.5\n4,5,6\n",
            "1, 2, 3\n4, 5, 6\n",
            "1,2,3\n4,5,6\n",
        ] {
            let t = table(text).unwrap();
            assert!(!t.decimal_comma, "{text:?}");
            assert_eq!((t.rows, t.cols), (2, 3), "{text:?}");
        }
    }

    #[test]
    fn byte_order_mark_header_lines_and_latin1() {
        let t = table(&decode(b"\xef\xbb\xbfh=650\nx y\n1 2 3\n4 5 6\n").unwrap()).unwrap();
        assert_eq!(t.header, ["h=650", "x y"]);
        assert_eq!(t.values, [1.0, 2.0, 3.0, 4.0, 5.0, 6.0]);
        let wide: Vec<u8> = "x in \u{b5}m,y\r\n1,2\r\n"
            .encode_utf16()
            .flat_map(u16::to_le_bytes)
            .collect();
        let t = table(&decode(&[b"\xff\xfe".as_slice(), &wide].concat()).unwrap()).unwrap();
        assert_eq!(
            (t.header.as_slice(), t.rows, t.cols),
            (["x in µm,y".to_string()].as_slice(), 1, 2)
        );
        let latin = decode(b"# Value units: \xb5m\n1 2 3\n").unwrap();
        assert!(latin.contains("µm"));
        assert!(decode(b"\x88\x1b\x03\x6f\0\0binary").is_err());
        let e = table("1 2 3\n4 five 6\n").unwrap_err();
        assert!(e.contains("line 2: 'five' is not a number"), "{e}");
    }

    #[test]
    fn maps_lists_and_profiles_told_apart() {
        let shape = |text: &str| classify(&table(text).unwrap());
        assert_eq!(shape("1 2 3\n4 5 6\n"), Shape::Matrix);
        assert_eq!(shape("0 0 1\n1 0 2\n0 1 3\n1 1 4\n"), Shape::Xyz);
        assert_eq!(shape("0 1\n1 2\n2 3\n"), Shape::LineScan);
        assert_eq!(shape("1\n2\n3\n"), Shape::LineScan);
        assert_eq!(shape("1 2 3 4 5\n"), Shape::LineScan);
        // Three columns that are no grid: a narrow matrix, unless the first only increases.
        assert_eq!(shape("1 2 3\n4 5 6\n7 8 9\n1 5 9\n"), Shape::Matrix);
        assert_eq!(
            shape("0 -9.9 1.4\n1 -9.8 1.5\n2 -9.7 1.3\n3 -9.6 1.2\n4 -9.5 1.1\n"),
            Shape::LineScan
        );
    }
}
