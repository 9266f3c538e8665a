//! CSV text as spreadsheets write it (RFC 4180): fields separated by commas, a field with a
//! comma, a quote or a line break quoted, a quote inside doubled. What a teacher's list of
//! submissions is read from, and what the class report's `report.csv` is written as.

use std::borrow::Cow;

/// The records of `text`, each a list of fields. Lines end in `\n` or `\r\n`; blank lines are
/// skipped; a byte-order mark at the start is ignored. The error names the line.
pub fn parse(text: &str) -> Result<Vec<Vec<String>>, String> {
    let text = text.strip_prefix('\u{feff}').unwrap_or(text);
    let mut records = Vec::new();
    let mut record = Vec::new();
    let mut field = String::new();
    let mut quoted = false;
    let mut line = 1;
    let mut started = line;
    let mut chars = text.chars().peekable();
    // Whether the field being read was opened by a quote (and so may not take more text
    // after its closing quote).
    let mut was_quoted = false;
    while let Some(c) = chars.next() {
        if quoted {
            match c {
                '"' if chars.peek() == Some(&'"') => {
                    chars.next();
                    field.push('"');
                }
                '"' => quoted = false,
                '\n' => {
                    line += 1;
                    field.push(c);
                }
                _ => field.push(c),
            }
            continue;
        }
        match c {
            '"' if field.is_empty() && !was_quoted => {
                quoted = true;
                was_quoted = true;
            }
            '"' => {
                return Err(format!(
                    "line {line}: a quote inside a field that is not quoted"
                ));
            }
            ',' => {
                record.push(std::mem::take(&mut field));
                was_quoted = false;
            }
            '\r' if chars.peek() == Some(&'\n') => {}
            '\n' => {
                record.push(std::mem::take(&mut field));
                was_quoted = false;
                if !(record.len() == 1 && record[0].is_empty()) {
                    records.push(std::mem::take(&mut record));
                }
                record.clear();
                line += 1;
                started = line;
            }
            _ if was_quoted => {
                return Err(format!("line {line}: text after a field's closing quote"));
            }
            _ => field.push(c),
        }
    }
    if quoted {
        return Err(format!("line {started}: a quote is never closed"));
    }
    record.push(field);
    if !(record.len() == 1 && record[0].is_empty()) {
        records.push(record);
    }
    Ok(records)
}

/// `value` as one CSV field: quoted (its quotes doubled) when it holds a comma, a quote or a
/// line break, or starts with a character a spreadsheet would take for a formula (`=`, `+`,
/// `-`, `@`: then a quote mark `'` is put before it, so a file name cannot run as a formula).
pub fn field(value: &str) -> Cow<'_, str> {
    let formula = value.starts_with(['=', '+', '-', '@']) && value.parse::<f64>().is_err();
    let value: Cow<str> = if formula {
        format!("'{value}").into()
    } else {
        value.into()
    };
    if value.contains([',', '"', '\n', '\r']) {
        format!("\"{}\"", value.replace('"', "\"\"")).into()
    } else {
        value
    }
}

/// One record: the fields joined by commas, and a line break.
pub fn record<'a>(fields: impl IntoIterator<Item = &'a str>) -> String {
    let mut line = fields.into_iter().map(field).collect::<Vec<_>>().join(",");
    line.push_str("\r\n");
    line
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn fields_quoted_or_not() {
        let text = "\u{feff}file,stage,light\r\nalice.png,lab,\"0,-0.5,-0.7\"\n\n\"bob \"\"b\"\".png\",,\n\"two\nlines\",x,y";
        let records = parse(text).unwrap();
        assert_eq!(
            records,
            [
                vec!["file", "stage", "light"],
                vec!["alice.png", "lab", "0,-0.5,-0.7"],
                vec!["bob \"b\".png", "", ""],
                vec!["two\nlines", "x", "y"],
            ]
        );
    }

    #[test]
    fn bad_quotes_name_their_line() {
        assert_eq!(
            parse("a,b\nc\"d,e").unwrap_err(),
            "line 2: a quote inside a field that is not quoted"
        );
        assert_eq!(
            parse("a\n\"b,c\nd").unwrap_err(),
            "line 2: a quote is never closed"
        );
        assert_eq!(
            parse("\"a\"b").unwrap_err(),
            "line 1: text after a field's closing quote"
        );
    }

    /// What is written reads back as it was.
    #[test]
    fn written_records_read_back() {
        let fields = [
            "plain",
            "a,b",
            "say \"hi\"",
            "two\nlines",
            "=SUM(A1)",
            "-0.5",
            "",
        ];
        let text = record(fields) + &record(["x"]);
        assert_eq!(
            text,
            "plain,\"a,b\",\"say \"\"hi\"\"\",\"two\nlines\",'=SUM(A1),-0.5,\r\nx\r\n"
        );
        let back = parse(&text).unwrap();
        assert_eq!(
            back[0],
            [
                "plain",
                "a,b",
                "say \"hi\"",
                "two\nlines",
                "'=SUM(A1)",
                "-0.5",
                ""
            ]
        );
        assert_eq!(back[1], ["x"]);
    }
}
