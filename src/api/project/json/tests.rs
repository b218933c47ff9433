//! The stepped reader against serde_json's one-go reading ([`read_at_once`]):
//! on hand-written edge cases, the fuzz corpus of project files, random
//! mutations of project texts and random JSON, at many step sizes, both
//! give the same value (numbers compared bit for bit) or both fail the
//! same way (the same limit message, bad base64, or a syntax error).
use super::*;
use proptest::prelude::*;
use std::path::Path;

/// `a` and `b` are the same value, numbers bit for bit (`-0` is not `0`).
fn same(a: &Value, b: &Value) -> bool {
    match (a, b) {
        (Value::Number(x), Value::Number(y)) => x.to_bits() == y.to_bits(),
        (Value::List(x), Value::List(y)) => {
            x.len() == y.len() && x.iter().zip(y).all(|(a, b)| same(a, b))
        }
        (Value::Object(x), Value::Object(y)) => {
            x.len() == y.len()
                && x.iter()
                    .zip(y)
                    .all(|((ka, a), (kb, b))| ka == kb && same(a, b))
        }
        _ => a == b,
    }
}

/// How a reading failed: the limit's message, bad base64, or a syntax error.
fn class(e: &Error) -> String {
    if e.kind() == "limit" {
        return e.to_string();
    }
    assert_eq!(e.kind(), "invalid-input", "{e}");
    if e.to_string() == NOT_BASE64 {
        "base64".into()
    } else {
        "syntax".into()
    }
}

/// Whether both readers agree on `text` with `fuel` per step.
fn agree(text: &str, fuel: usize) -> std::result::Result<(), String> {
    let once = read_at_once(text);
    let stepped = read_stepped(text, fuel);
    let ok = match (&once, &stepped) {
        (Ok(a), Ok(b)) => same(a, b),
        (Err(a), Err(b)) => {
            let c = class(b);
            if c == "syntax" && !b.to_string().contains(" at line ") {
                return Err(format!("{text:?}: a syntax error without its place: {b}"));
            }
            class(a) == c
        }
        _ => false,
    };
    if ok {
        Ok(())
    } else {
        let short: String = text.chars().take(300).collect();
        Err(format!(
            "{short:?} (fuel {fuel}): at once {once:?}, stepped {stepped:?}"
        ))
    }
}

const FUELS: &[usize] = &[1, 2, 3, 5, 8, 17, 64, 1 << 20];

fn check_all(text: &str) {
    for &f in FUELS {
        agree(text, f).unwrap();
    }
}

fn edge_cases() -> Vec<String> {
    let mut v: Vec<String> = [
        "",
        " ",
        "\n",
        "null",
        "nul",
        "nulx",
        "n",
        "true",
        "tru",
        "false",
        "fals",
        "truefalse",
        "null ",
        " null\n",
        "\tnull\r\n",
        "\u{c}null",
        "\u{feff}null",
        "null\u{0}",
        "\u{a0}1",
        "NaN",
        "Infinity",
        "-Infinity",
        "undefined",
        "'a'", // numbers
        "0",
        "-0",
        "-",
        "-a",
        "--1",
        "+1",
        "01",
        "-01",
        "00",
        "0.",
        "0.5",
        ".5",
        "1.e5",
        "1e",
        "1e+",
        "1e-",
        "1E5",
        "1e-5",
        "1.5e+300",
        "1e400",
        "-1e400",
        "1e-400",
        "0e400",
        "18446744073709551615",
        "18446744073709551616",
        "-9223372036854775808",
        "-9223372036854775809",
        "9007199254740993",
        "123456789012345678901234567890",
        "0.1234567890123456789012345678901",
        "1e2147483647",
        "1e2147483648",
        "0e99999999999",
        "1e-99999999999",
        "-0e99999999999",
        "2.2250738585072011e-308",
        "4.9e-324",
        "2e-324",
        "1.7976931348623157e308",
        "1.7976931348623159e308",
        "0.0",
        "-0.0",
        "1.0e0",
        "1E+0",
        "5e-0",
        "1x",
        "1.5.5",
        "1e5e5",
        "-.5",
        "1.5e",
        "0x10",
        // strings
        r#""""#,
        r#""abc""#,
        r#""a\"b""#,
        r#""\/\b\f\n\r\t\\""#,
        r#""\u0041""#,
        r#""\u00e9\u00E9""#,
        r#""\ud83d\ude00""#,
        r#""\uD83D\uDE00""#,
        r#""\ud83d""#,
        r#""\ude00""#,
        r#""\ud83d\u0041""#,
        r#""\ud83dx""#,
        r#""\ud83d\n""#,
        r#""\ud83d\ud83d\ude00""#,
        r#""\u12""#,
        r#""\u12G4""#,
        r#""\x""#,
        r#""\'""#,
        "\"a\nb\"",
        "\"a\tb\"",
        "\"\u{7f}\"",
        "\"\u{1f}\"",
        "\"\u{0}\"",
        "\"é😀\"",
        "\"abc",
        "\"abc\\",
        "\"\\u",
        "\"\\u00",
        "\"\\ud83d\\",
        "\"\\ud83d\\u",
        "\"\\ud83d\\ude0",
        r#""\u0000""#,
        r#""\uffff""#,
        r#""\uFFFE""#,
        // lists and objects
        "[]",
        "[ ]",
        "[1,2]",
        "[1,]",
        "[1 ,]",
        "[,1]",
        "[,]",
        "[1 2]",
        "[",
        "[1",
        "[1,",
        "]",
        "[[]]",
        "[[],[[]]]",
        "[null,true,false,\"x\",1.5,{}]",
        "[}",
        "[1}",
        "{]",
        "{}",
        "{ }",
        r#"{"a":1}"#,
        r#"{"a" : 1 , "b":[2]}"#,
        r#"{"a":1,}"#,
        "{,}",
        "{1:2}",
        r#"{"a"}"#,
        r#"{"a":}"#,
        r#"{"a" 1}"#,
        r#"{"a":1 "b":2}"#,
        "{",
        r#"{"a""#,
        r#"{"a":"#,
        r#"{"a":1"#,
        r#"{"a":1,"#,
        r#"{"a":1,"a":2}"#,
        r#"{"a":1,"b":2,"a":3}"#,
        r#"{"a":[1],"a":{"b":2},"a":null}"#,
        r#"{"":1,"":2}"#,
        r#"{"\u0061":1,"a":2}"#,
        r#"{'a':1}"#,
        r#"{"a":1,,"b":2}"#,
        r#"{"a"::1}"#,
        // $bytes
        r#"{"$bytes":"TWFu"}"#,
        r#"{"$bytes":"TWE="}"#,
        r#"{"$bytes":"TWE"}"#,
        r#"{"$bytes":"T"}"#,
        r#"{"$bytes":""}"#,
        r#"{"$bytes":" TW\nFu "}"#,
        r#"{"$bytes":"TW=u"}"#,
        r#"{"$bytes":"TWF*"}"#,
        r#"{"$bytes":"TWFuT"}"#,
        r#"{"$bytes":"T==="}"#,
        r#"{"$bytes":"===="}"#,
        r#"{"$bytes":"AB="}"#,
        r#"{"$bytes":"AB=="}"#,
        r#"{"$bytes":"AB= ="}"#,
        r#"{"$bytes":"A==="}"#,
        r#"{"$bytes":"ABC=\t"}"#,
        r#"{"$bytes":"ABC==="}"#,
        r#"{"$bytes":"=ABC"}"#,
        r#"{"$bytes":"AB=C"}"#,
        r#"{"$bytes":"AB\fC"}"#,
        r#"{"$bytes":"AB\u000bC"}"#,
        r#"{"$bytes":"é"}"#,
        r#"{"$bytes":"-_"}"#,
        r#"{"$bytes":"+/+/"}"#,
        r#"{"$bytes":5}"#,
        r#"{"$bytes":null}"#,
        r#"{"$bytes":["TWFu"]}"#,
        r#"{"$bytes":"TWFu","x":1}"#,
        r#"{"x":1,"$bytes":"TWFu"}"#,
        r#"{"$bytes":"!!","$bytes":"TWFu"}"#,
        r#"{"$bytes":"TWFu","$bytes":1}"#,
        r#"{"$bytes":"TWFu"} x"#,
        r#"[{"$bytes":"!"}, x]"#,
        r#"[{"$bytes":"!"}"#,
        r#"{"$bytes":"\u0041\u0041=="}"#,
        r#"{"$bytes":{"$bytes":"TWFu"}}"#,
        r#"{"$bytes":"TWFu""#,
        r#"{"$Bytes":"TWFu"}"#,
        r#"{"$bytes ":"TWFu"}"#,
        // trailing characters
        "1 2",
        "{} {}",
        "[] x",
        "null x",
        "\"a\" \"b\"",
        "[1x]",
        "truex",
        "[truex]",
        "[nullnull]",
        "[1]]",
        "{}}",
        "[1] \n\n  ",
        "[1]\n\n  x",
    ]
    .iter()
    .map(|s| s.to_string())
    .collect();
    let n = limits::MAX_STATE_DEPTH;
    for d in [n - 1, n, n + 1, n + 5] {
        v.push(format!("{}{}", "[".repeat(d), "]".repeat(d)));
        v.push("[".repeat(d));
        v.push(format!("{}x", "[".repeat(d)));
        v.push(format!("{}1{}", r#"{"a":"#.repeat(d), "}".repeat(d)));
        v.push(format!("{}{{}}{}", "[".repeat(d - 1), "]".repeat(d - 1)));
        v.push(format!("{}{{\"$bytes\":\"!\"}}", "[".repeat(d - 1)));
    }
    v.push("[".repeat(100_000));
    v.push(format!("\"{}\"", "x".repeat(100_000)));
    v.push(format!("{}1", "0".repeat(1000)));
    v.push(format!("1{}", "0".repeat(1000)));
    v.push(format!("1{}e-1000", "0".repeat(1000)));
    v.push(format!("0.{}1", "0".repeat(1000)));
    v.push(format!(
        "{}null{}",
        " \n".repeat(5000),
        "\r\n\t".repeat(5000)
    ));
    v.push(format!(
        r#"{{"$bytes":"{}"}}"#,
        super::super::base64_encode(&(0..=255u8).cycle().take(10_001).collect::<Vec<_>>())
    ));
    v
}

#[test]
fn edge_cases_read_as_serde_json_reads_them() {
    for t in edge_cases() {
        check_all(&t);
    }
}

/// The value limit: exactly the limit reads, one more is refused, the same
/// way both readers (also when the extra value is bad JSON or a list).
#[test]
fn the_value_limit_is_the_same() {
    let n = limits::MAX_STATE_VALUES;
    // The list itself is a value.
    let list = |zeros: usize, last: &str| format!("[{}{last}]", "0,".repeat(zeros));
    for text in [
        list(n - 2, "0"),
        list(n - 1, "0"),
        list(n - 1, "01"),
        list(n - 1, "[x"),
        list(n - 2, "\"\\q\""),
        list(n - 1, "\"\\q\""),
    ] {
        for fuel in [1 << 10, 1 << 20] {
            agree(&text, fuel).unwrap();
        }
    }
    let e = read_stepped(&list(n - 1, "0"), 1 << 20).unwrap_err();
    assert_eq!(e.kind(), "limit");
    assert!(read_stepped(&list(n - 2, "0"), 1 << 20).is_ok());
}

#[test]
fn syntax_errors_say_what_and_where() {
    let e = read_stepped("{\"a\": 1,\n  \"b\" 2}", 4).unwrap_err();
    assert_eq!(e.to_string(), "expected `:` after a key at line 2 column 7");
    let e = read_stepped("[1,\n\n 2,]", 1 << 20).unwrap_err();
    assert_eq!(
        e.to_string(),
        "a comma before `]` (trailing comma) at line 3 column 4"
    );
    let e = read_stepped("\"a\u{1}\"", 1).unwrap_err();
    assert_eq!(
        e.to_string(),
        "a control character (U+0000 to U+001F) inside a string at line 1 column 3"
    );
    let e = read_stepped("[1e999]", 1 << 20).unwrap_err();
    assert_eq!(e.to_string(), "a number out of range at line 1 column 2");
}

#[test]
fn every_project_in_the_fuzz_corpus_reads_the_same() {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("fuzz/corpus/project");
    let mut n = 0;
    for f in std::fs::read_dir(&dir).unwrap() {
        let data = std::fs::read(f.unwrap().path()).unwrap();
        // As the page reads a file: invalid UTF-8 replaced.
        let text = String::from_utf8_lossy(&data);
        for fuel in [1, 7, 300, 1 << 20] {
            agree(&text, fuel).unwrap();
        }
        n += 1;
    }
    assert!(n >= 100, "only {n} corpus files");
}

/// Big steps end: a reader that is spent says so instead of reading on.
#[test]
fn a_spent_reader_refuses_to_go_on() {
    let mut r = Reader::new();
    assert_eq!(
        r.step("[1]", 100).unwrap(),
        Some(Value::List(vec![Value::Number(1.0)]))
    );
    assert!(r.step("[1]", 100).is_err());
    let mut r = Reader::new();
    assert!(r.step("[x]", 100).is_err());
    assert!(r.step("[x]", 100).is_err());
}

/// Seeds the mutations start from: small project files and JSON.
fn seeds() -> Vec<String> {
    vec![
        r#"{"format":"filigree-project","version":2,"tool":"pixel","stateVersion":1,"state":{"mask":{"width":2,"height":1,"bits":{"$bytes":"AAE="}},"strokes":[[[0,0],[1.5,-2e-3]]],"names":{"source":"a\u00e9.png"}}}"#.into(),
        r#"{"format":"filigree-project","version":1,"tool":"fit","state":{"program":"circle(0.5, 0.5, r);\n","values":[0.5,2],"target":{"width":1,"height":1,"rgba":{"$bytes":"AQIDBA=="}}}}"#.into(),
        "[1, -0, 0.5e10, \"\\ud83d\\ude00\\n\", {\"$bytes\": \"TWFu\"}, [[[]]], {\"a\":1,\"a\":2}, true, null]".into(),
        "{\"$bytes\" : \" TW Fu\\nTQ== \" , \"$bytes\":\"AB\"}".into(),
    ]
}

/// Characters mutations insert: JSON's own, digits, escapes, base64, odd ones.
const ALPHABET: &[char] = &[
    '{', '}', '[', ']', ',', ':', '"', '\\', 'u', 'd', '8', '3', 'D', 'c', '0', '1', '9', '-', '+',
    '.', 'e', 'E', ' ', '\n', '\t', '\r', '$', 'b', 'y', 't', 's', '=', '/', 'n', 'l', 'a', 'f',
    'x', '\u{1}', '\u{c}', 'é', '😀', '\u{a0}',
];

fn mutate(seed: &str, edits: &[(usize, u8, usize)]) -> String {
    let mut s: Vec<char> = seed.chars().collect();
    for &(at, op, c) in edits {
        let at = at % (s.len() + 1);
        let c = ALPHABET[c % ALPHABET.len()];
        match op % 4 {
            0 => s.insert(at, c),
            1 if at < s.len() => {
                s.remove(at);
            }
            2 if at < s.len() => s[at] = c,
            3 => s.truncate(at),
            _ => s.push(c),
        }
    }
    s.into_iter().collect()
}

/// Random JSON values (with `$bytes` objects, escapes, all number shapes).
fn json_value() -> impl Strategy<Value = String> {
    let number = prop_oneof![
        any::<i64>().prop_map(|v| v.to_string()),
        any::<u64>().prop_map(|v| v.to_string()),
        any::<f64>()
            .prop_filter("finite", |v| v.is_finite())
            .prop_map(|v| format!("{v:e}")),
        any::<f64>()
            .prop_filter("finite", |v| v.is_finite())
            .prop_map(|v| format!("{v}")),
        "-?(0|[1-9][0-9]{0,30})(\\.[0-9]{1,30})?([eE][+-]?[0-9]{1,4})?",
    ];
    let string = prop_oneof![
        ".{0,12}".prop_map(|s| serde_json::to_string(&s).unwrap()),
        "[a-zA-Z0-9+/= \\n]{0,16}".prop_map(|s| serde_json::to_string(&s).unwrap()),
        "\"(\\\\u[0-9a-fA-F]{4}|\\\\[nrtbf/\\\\\"]|[a-z])*\"",
    ];
    let leaf = prop_oneof![
        Just("null".to_string()),
        Just("true".to_string()),
        Just("false".to_string()),
        number,
        string.clone(),
        "[a-zA-Z0-9+/= ]{0,16}".prop_map(|s| format!(r#"{{"$bytes":"{s}"}}"#)),
    ];
    leaf.prop_recursive(5, 48, 6, move |inner| {
        prop_oneof![
            (prop::collection::vec(inner.clone(), 0..6), "[ \n]{0,2}")
                .prop_map(|(v, ws)| format!("[{ws}{}]", v.join(&format!(",{ws}")))),
            prop::collection::vec((string.clone(), inner), 0..6).prop_map(|kv| {
                let kv: Vec<String> = kv.into_iter().map(|(k, v)| format!("{k}:{v}")).collect();
                format!("{{{}}}", kv.join(","))
            }),
        ]
    })
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(3000))]

    /// Random edits of project texts: the same value or the same failure.
    #[test]
    fn mutated_projects_read_the_same(
        seed in 0usize..4,
        edits in prop::collection::vec((any::<usize>(), any::<u8>(), any::<usize>()), 1..6),
        fuel in 1usize..40,
    ) {
        let text = mutate(&seeds()[seed], &edits);
        prop_assert!(agree(&text, fuel).is_ok(), "{}", agree(&text, fuel).unwrap_err());
        prop_assert!(agree(&text, 1 << 20).is_ok(), "{}", agree(&text, 1 << 20).unwrap_err());
    }

    /// Random JSON, and random JSON with one edit.
    #[test]
    fn random_json_reads_the_same(
        text in json_value(),
        edit in (any::<usize>(), any::<u8>(), any::<usize>()),
        fuel in 1usize..40,
    ) {
        prop_assert!(agree(&text, fuel).is_ok(), "{}", agree(&text, fuel).unwrap_err());
        let text = mutate(&text, &[edit]);
        prop_assert!(agree(&text, fuel).is_ok(), "{}", agree(&text, fuel).unwrap_err());
    }
}
