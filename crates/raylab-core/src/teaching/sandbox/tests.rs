//! The language's tests: its errors (message, line and column), pasted C++, values against
//! glam's, one lane against sixteen, and random and mutated texts that must never panic.

use glam::Vec3;

use super::*;
use crate::base::sampling::Rng;

/// The one error of `source`.
fn error_of(source: &str) -> SandboxError {
    match compile(source) {
        Ok(_) => panic!("{source:?} compiled"),
        Err(errors) => {
            assert_eq!(errors.len(), 1, "{source:?}: {errors:?}");
            errors[0].clone()
        }
    }
}

/// Asserts `source`'s error is `message` at `line`:`column`, underlining `underlined`.
fn assert_error(source: &str, line: usize, column: usize, underlined: &str, message: &str) {
    let e = error_of(source);
    assert_eq!(e.message, message, "{source:?}");
    assert_eq!((e.line, e.column), (line, column), "{source:?}: {e}");
    assert_eq!(
        &source[e.span.start..e.span.end],
        underlined,
        "{source:?}: {e}"
    );
}

/// Inputs for one pixel: every component set from `values` by name, the rest 0.
fn inputs(values: &[(&str, &[f32])]) -> Vec<f32> {
    let mut out = vec![0.0; INPUT_COMPONENTS];
    for (name, v) in values {
        let i = input(name).unwrap();
        for (k, x) in v.iter().enumerate() {
            out[usize::from(i.offset) + k] = *x;
        }
    }
    out
}

/// Quantity `q` of `source` at one pixel.
fn eval(source: &str, q: Quantity, values: &[(&str, &[f32])]) -> [f32; 3] {
    let eq = compile(source).unwrap_or_else(|e| panic!("{source:?}: {e:?}"));
    eq.tape(q)
        .unwrap()
        .run_one(&inputs(values), &mut Vec::new())
}

#[test]
fn the_issues_messages_with_their_lines_and_columns() {
    assert_error(
        "let r = lightPos - position\nD = vec3(dot(r, 2.0))",
        2,
        10,
        "dot(r, 2.0)",
        "`dot` takes two vec3, got vec3 and a number",
    );
    assert_error(
        "// the light\nlet r = lightpos - position\nR = color * r",
        2,
        9,
        "lightpos",
        "unknown name `lightpos`: did you mean `lightPos`?",
    );
}

#[test]
fn each_message_names_the_fix_where_it_is() {
    let cases: &[(&str, usize, usize, &str, &str)] = &[
        (
            "R = colour",
            1,
            5,
            "colour",
            "unknown name `colour`: did you mean `color`?",
        ),
        (
            "R = normalise(normal)",
            1,
            5,
            "normalise",
            "unknown function `normalise`: did you mean `normalize`?",
        ),
        (
            "D = length(2.0) * lightColor",
            1,
            5,
            "length(2.0)",
            "`length` takes one vec3, got a number",
        ),
        (
            "R = max(color, true)",
            1,
            5,
            "max(color, true)",
            "`max` takes two numbers, two vec3, or a vec3 and a number, got vec3 and a bool",
        ),
        (
            "shadowed = shadowDistance < lightPos",
            1,
            12,
            "shadowDistance < lightPos",
            "`<` compares two numbers, got a number and vec3: compare a part (`.x`) or a `length`",
        ),
        (
            "D = shadowed ? 0 : lightColor",
            1,
            5,
            "shadowed ? 0 : lightColor",
            "the two choices of `c ? a : b` must be of one type, got a number and vec3: write \
             `vec3(0)` for a vec3 of zeros",
        ),
        (
            "R = shadowDistance ? color : D",
            1,
            5,
            "shadowDistance",
            "the condition of `c ? a : b` must be a bool, got a number: compare it, e.g. `x > 0`",
        ),
        (
            "shadowed = 1.0",
            1,
            12,
            "1.0",
            "`shadowed` (whether the light is blocked) must be a bool, got a number: compare it, \
             e.g. `shadowDistance < …`",
        ),
        (
            "R = dot(color, D)",
            1,
            5,
            "dot(color, D)",
            "`R` (the pixel's value) must be vec3, got a number: write `vec3(…)` of it, or \
             multiply it by a vec3",
        ),
        (
            "d = right * x + shadowDistance * forward",
            1,
            17,
            "shadowDistance",
            "`shadowDistance` is not known when computing `d` (the camera ray's direction): it \
             may use x, y, W, H, focalLength, cameraPos, right, down, forward",
        ),
        (
            "D = R",
            1,
            5,
            "R",
            "`R` (the pixel's value) is the last quantity computed: nothing uses it",
        ),
        (
            "shadowed = D.x > 0",
            1,
            12,
            "D",
            "`D` is computed after `shadowed`: `shadowed` cannot use it",
        ),
        (
            "D = D * 2",
            1,
            5,
            "D",
            "`D` cannot use itself (no recursion): write it from the lab's inputs",
        ),
        (
            "R = r * color\nlet r = 2",
            1,
            5,
            "r",
            "`r` is defined below, on line 2: move it above this line",
        ),
        (
            "r = 2 * color",
            1,
            1,
            "r",
            "`r` is not a quantity: did you mean `R`? For a value of your own, write `let r = …`",
        ),
        (
            "let position = 2",
            1,
            5,
            "position",
            "`position` is the lab's input (the hit's position), not yours to set: name your \
             value something else",
        ),
        (
            "let a = 1\nlet a = 2",
            2,
            5,
            "a",
            "`a` is already defined on line 1: give this value another name",
        ),
        (
            "R = color\n\nR = D",
            3,
            1,
            "R",
            "`R` is already written on line 1: write each quantity once",
        ),
        (
            "float r2 = lightPos - position;",
            1,
            12,
            "lightPos - position",
            "`r2` is declared float but its value is vec3: declare it `vec3`",
        ),
        (
            "R = color.w",
            1,
            10,
            ".w",
            "a vec3's parts are `.x`, `.y` and `.z`, found `.w`",
        ),
        (
            "R = color +",
            1,
            12,
            "",
            "expected a number, a name or `(`, found the end of the text",
        ),
        (
            "R = (color * D",
            1,
            15,
            "",
            "expected `)` to close `(`, found the end of the text",
        ),
        (
            "R = color D",
            1,
            11,
            "D",
            "expected an operator or the end of the line, found `D`",
        ),
        (
            "R = color & D",
            1,
            11,
            "&",
            "`&` is not an operator here: write `&&` for \"and\"",
        ),
        (
            "R = color; # D",
            1,
            12,
            "#",
            "unexpected character `#`: no preprocessor lines; paste only the formula",
        ),
        (
            "int n = 2",
            1,
            1,
            "int",
            "`int` is not a type here: use `float` for numbers, `vec3`, or `let`",
        ),
        (
            "shadowed = !shadowDistance",
            1,
            12,
            "!shadowDistance",
            "`!` takes a bool, got a number: compare it first, e.g. `x > 0`",
        ),
        (
            "shadowed = shadowDistance > 0 && 1",
            1,
            12,
            "shadowDistance > 0 && 1",
            "`&&` takes two bools, got a bool and a number: compare numbers first, e.g. `x > 0`",
        ),
        (
            "R = dot",
            1,
            5,
            "dot",
            "`dot` is a function: call it, as `dot(…)`",
        ),
        (
            "R = color * /* unclosed\n D",
            1,
            13,
            "/*",
            "this `/*` comment is never closed: end it with `*/`",
        ),
    ];
    for &(source, line, column, underlined, message) in cases {
        assert_error(source, line, column, underlined, message);
    }
}

/// Columns count characters, not bytes: an error after a `ρ` in a comment is where it looks.
#[test]
fn columns_count_characters() {
    let e = error_of("/* ρ */ R = colr");
    assert_eq!((e.line, e.column), (1, 13), "{e}");
    assert_eq!(e.message, "unknown name `colr`: did you mean `color`?");
}

/// Several statements' errors at once, in the order of the text.
#[test]
fn every_statement_reports_its_own_error() {
    for source in [
        "let a = 1 + ;\nR = color D\nD = )",
        "R = colr\nshadowed = 1\nD = vec3(1, 2)",
    ] {
        let errors = compile(source).unwrap_err();
        let lines: Vec<usize> = errors.iter().map(|e| e.line).collect();
        assert_eq!(lines, [1, 2, 3], "{errors:?}");
    }
}

#[test]
fn pasted_cpp_lines_compile() {
    let source = "\
        // DirectLight, as a student writes it\n\
        glm::vec3 r = lightPos - position;\n\
        float r2 = glm::dot(r, r);\n\
        const float cosTheta = std::max(glm::dot(glm::normalize(r), normal), 0.0f);\n\
        vec3 B = lightColor / (4.f * M_PI * r2);\n\
        bool inShadow = shadowDistance < glm::length(r);\n\
        shadowed = inShadow;\n\
        vec3 D = shadowed ? glm::vec3(0.0f, 0.0f, 0.0f) : B * cosTheta;\n\
        R = color * (D + indirectLight); // equation 30\n\
        d = right * (x + 0.5f - W / 2.f) + down * (y + 0.5f - H / 2) + forward * focalLength;\n";
    let eq = compile(source).unwrap_or_else(|e| panic!("{e:?}"));
    let written: Vec<Quantity> = eq.written().collect();
    assert_eq!(
        written,
        [
            Quantity::Direction,
            Quantity::Shadowed,
            Quantity::Direct,
            Quantity::Value
        ]
    );
    // Statements may also share a line, and a line may go on inside parentheses or after an
    // operator.
    let eq = compile("let a = 2; let b = (a +\n 1) *\n 3; R = vec3(b)").unwrap();
    let r = eq
        .tape(Quantity::Value)
        .unwrap()
        .run_one(&inputs(&[]), &mut Vec::new());
    assert_eq!(r, [9.0; 3]);
    // The C literals.
    for (literal, value) in [
        ("14.f", 14.0),
        ("14.0f", 14.0),
        (".5", 0.5),
        ("1e-4", 1e-4),
        ("2.5e+1f", 25.0),
    ] {
        let r = eval(&format!("R = vec3({literal})"), Quantity::Value, &[]);
        assert_eq!(r, [value; 3], "{literal}");
    }
}

/// The language's values are glam's, bit for bit, where glam has the operation.
#[test]
fn values_are_glams() {
    let mut rng = Rng::new(7);
    for _ in 0..500 {
        let mut v = || {
            Vec3::new(
                rng.uniform(-3.0, 3.0),
                rng.uniform(-3.0, 3.0),
                rng.uniform(-3.0, 3.0),
            )
        };
        let (a, b) = (v(), v());
        let given: [(&str, &[f32]); 2] = [("lightPos", &a.to_array()), ("position", &b.to_array())];
        let cases: [(&str, Vec3); 9] = [
            ("R = vec3(dot(lightPos, position))", Vec3::splat(a.dot(b))),
            ("R = cross(lightPos, position)", a.cross(b)),
            ("R = normalize(lightPos)", a.normalize()),
            (
                "R = vec3(length(lightPos - position))",
                Vec3::splat((a - b).length()),
            ),
            ("R = lightPos / length(lightPos)", a / a.length()),
            ("R = max(lightPos, position)", a.max(b)),
            ("R = abs(lightPos) * 2 - position", a.abs() * 2.0 - b),
            (
                "R = clamp(lightPos, 0.0, 1.0)",
                a.max(Vec3::ZERO).min(Vec3::ONE),
            ),
            (
                "R = mix(lightPos, position, 0.25)",
                a * (1.0 - 0.25) + b * 0.25,
            ),
        ];
        for (source, want) in cases {
            let got = Vec3::from_array(eval(source, Quantity::Value, &given));
            assert_eq!(
                got.to_array().map(f32::to_bits),
                want.to_array().map(f32::to_bits),
                "{source}"
            );
        }
    }
    let r = eval("R = vec3(pi, M_PI, 4 * pi)", Quantity::Value, &[]);
    assert_eq!(
        r,
        [
            std::f32::consts::PI,
            std::f32::consts::PI,
            4.0 * std::f32::consts::PI
        ]
    );
    let r = eval(
        "R = vec3(2 < 3 ? 1 : 0, (1 == 1) && !(2 >= 3) ? 1 : 0, vec3(1, 2, 3) == vec3(1, 2, 3) ? 7 : 0)",
        Quantity::Value,
        &[],
    );
    assert_eq!(r, [1.0, 1.0, 7.0]);
}

/// A program with every operation, run over sixteen random pixels at once and one at a time:
/// the same bits, NaN and infinity included.
#[test]
fn sixteen_lanes_give_one_lanes_bits() {
    let source = "\
        let r = lightPos - position\n\
        let c = dot(normalize(r), normal)\n\
        let k = pow(abs(c), 1.5) + sqrt(abs(distance)) - min(c, 0.5) / max(distance, -1)\n\
        shadowed = shadowDistance < length(r) || !(c > 0) && c != 0.25\n\
        D = shadowed ? vec3(0) : clamp(lightColor * k / (4 * pi * dot(r, r)), -1, 1e3)\n\
        R = mix(color, cross(D, normal), color.x) + indirectLight / distance\n";
    let eq = compile(source).unwrap();
    let mut rng = Rng::new(3);
    let mut special = [
        0.0,
        -0.0,
        f32::INFINITY,
        f32::NEG_INFINITY,
        f32::NAN,
        1e-38,
        0.25,
    ];
    for round in 0..200 {
        let lanes: Vec<[f32; 16]> = (0..INPUT_COMPONENTS)
            .map(|_| {
                std::array::from_fn(|_| {
                    if rng.next_f32() < 0.1 {
                        special.rotate_left(1);
                        special[0]
                    } else {
                        rng.uniform(-2.0, 2.0)
                    }
                })
            })
            .collect();
        for q in eq.written() {
            let tape = eq.tape(q).unwrap();
            let sixteen = tape.run::<16>(&lanes, &mut Vec::new());
            for i in 0..16 {
                let one: Vec<f32> = lanes.iter().map(|l| l[i]).collect();
                let one = tape.run_one(&one, &mut Vec::new());
                let lane = [sixteen[0][i], sixteen[1][i], sixteen[2][i]];
                assert_eq!(
                    one.map(f32::to_bits),
                    lane.map(f32::to_bits),
                    "{q:?} round {round} lane {i}"
                );
            }
        }
    }
}

/// The caps: a text too long, an expression nested too deeply or too long, each refused with a
/// message (never a stack overflow).
#[test]
fn sizes_are_capped() {
    let long = format!("R = color{}", " ".repeat(MAX_SOURCE_BYTES));
    let e = error_of(&long);
    assert!(e.message.contains("over the 16384 allowed"), "{e}");
    let deep = format!("R = {}color{}", "(".repeat(1_000), ")".repeat(1_000));
    let e = error_of(&deep);
    assert!(
        e.message.starts_with("nested too deeply (over 64 levels)"),
        "{e}"
    );
    let negated = format!("R = {}color", "-".repeat(1_000));
    let e = error_of(&negated);
    assert!(e.message.starts_with("nested too deeply"), "{e}");
    let wide = format!("R = color{}", " + color".repeat(1500));
    let e = error_of(&wide);
    assert!(
        e.message
            .starts_with("this expression is too long (over 2000 parts)"),
        "{e}"
    );
    // Values reused by reference are computed once: a chain of lets doubling is still small.
    let mut chain = String::from("let a0 = color\n");
    for i in 1..60 {
        chain.push_str(&format!("let a{i} = a{} + a{}\n", i - 1, i - 1));
    }
    chain.push_str("R = a59");
    let eq = compile(&chain).unwrap();
    assert!(eq.tape(Quantity::Value).unwrap().ops.len() < 400);
}

/// The parts the inspector shows: each value of the student's own and each operation, call or
/// `.x` a quantity computes, statement by statement in the text's order (each one's parts in
/// the order computed, itself last), with line, column and text (its parentheses included);
/// a value used twice is one part, and its value is the tape's.
#[test]
fn parts_are_the_texts_values_in_order() {
    let source = "let r = lightPos - position\nvec3 n = normal; let unused = 2 * 3\n\
                  D = lightColor * (dot(r, n) /\n  dot(r,   r)) + vec3(r.x)\n";
    let eq = compile(source).unwrap();
    let parts: Vec<(usize, usize, Option<&str>, &str)> = eq
        .parts(Quantity::Direct)
        .iter()
        .map(|p| (p.line, p.column, p.name.as_deref(), p.text.as_str()))
        .collect();
    assert_eq!(
        parts,
        [
            (1, 5, Some("r"), "lightPos - position"),
            (2, 6, Some("n"), "normal"),
            (3, 19, None, "dot(r, n)"),
            (4, 3, None, "dot(r, r)"),
            (3, 18, None, "(dot(r, n) / dot(r, r))"),
            (3, 5, None, "lightColor * (dot(r, n) / dot(r, r))"),
            (4, 23, None, "r.x"),
            (4, 18, None, "vec3(r.x)"),
            (
                3,
                1,
                Some("D"),
                "lightColor * (dot(r, n) / dot(r, r)) + vec3(r.x)"
            ),
        ]
    );
    assert!(eq.parts(Quantity::Value).is_empty());
    let tape = eq.tape(Quantity::Direct).unwrap();
    let given = inputs(&[
        ("lightPos", &[1.0, 2.0, 3.0]),
        ("position", &[0.5, 0.25, -1.0]),
        ("normal", &[0.0, 1.0, 0.0]),
        ("lightColor", &[14.0; 3]),
    ]);
    let lanes: Vec<[f32; 1]> = given.iter().map(|&v| [v]).collect();
    let mut slots = Vec::new();
    let d = tape.run::<1>(&lanes, &mut slots).map(|[v]| v);
    let r = Vec3::new(0.5, 1.75, 4.0);
    let values: Vec<[f32; 3]> = eq
        .parts(Quantity::Direct)
        .iter()
        .map(|p| p.value(&slots))
        .collect();
    assert_eq!(values[0], r.to_array());
    assert_eq!(values[3], [r.dot(r); 3]);
    assert_eq!(values[6], [r.x; 3]);
    assert_eq!(values[8], d);
}

/// Random texts, and the lab's own text mutated (bytes deleted, swapped, inserted, lines
/// duplicated): compiling never panics, every error's span lies in the text on character
/// boundaries, and what compiles runs.
#[test]
fn random_and_mutated_texts_never_panic() {
    let seeds = [
        "let r = lightPos - position;\nfloat r2 = dot(r, r);\nshadowed = shadowDistance < sqrt(r2);\n\
         D = shadowed ? vec3(0) : lightColor * max(dot(r / sqrt(r2), normal), 0.0f) / (4 * M_PI * r2);\n\
         R = color * (D + indirectLight);\nd = right * (x + 0.5 - W / 2) + down * (y + .5 - H / 2) + forward * focalLength; // eq 24",
        "vec3 D = glm::clamp(mix(color, vec3(1, 2, 3e-2), 0.5), 0, 1); /* c */ R = -D.x * cross(D, normal) + pow(abs(D), vec3(2))",
    ];
    let alphabet: Vec<char> = "abcdxyzDR=+-*/().,;:?!<>&|  \n\t0123456789ef_ρ#{}[]/*\"'\\"
        .chars()
        .collect();
    let mut rng = Rng::new(11);
    let pick = |rng: &mut Rng, n: usize| (rng.next_u32() as usize) % n.max(1);
    let check = |text: &str| match compile(text) {
        Ok(eq) => {
            for q in eq.written() {
                let tape = eq.tape(q).unwrap();
                let out = tape.run_one(&[0.5; INPUT_COMPONENTS], &mut Vec::new());
                assert_eq!(out.len(), 3);
            }
        }
        Err(errors) => {
            assert!(!errors.is_empty());
            for e in errors {
                assert!(
                    e.span.start <= e.span.end && e.span.end <= text.len(),
                    "{text:?}: {e:?}"
                );
                assert!(text.is_char_boundary(e.span.start), "{text:?}: {e:?}");
                assert!(e.line >= 1 && e.column >= 1 && !e.message.is_empty());
            }
        }
    };
    for _ in 0..3000 {
        let len = pick(&mut rng, 60);
        let text: String = (0..len)
            .map(|_| alphabet[pick(&mut rng, alphabet.len())])
            .collect();
        check(&text);
    }
    for _ in 0..3000 {
        let mut chars: Vec<char> = seeds[pick(&mut rng, seeds.len())].chars().collect();
        for _ in 0..1 + pick(&mut rng, 4) {
            let i = pick(&mut rng, chars.len());
            match pick(&mut rng, 4) {
                0 if !chars.is_empty() => {
                    chars.remove(i);
                }
                1 if chars.len() > 1 => {
                    let j = pick(&mut rng, chars.len());
                    chars.swap(i, j);
                }
                2 => chars.insert(i.min(chars.len()), alphabet[pick(&mut rng, alphabet.len())]),
                _ => {
                    let j = (i + pick(&mut rng, 40)).min(chars.len());
                    let copy: Vec<char> = chars[i.min(j)..j].to_vec();
                    chars.splice(i..i, copy);
                }
            }
        }
        check(&chars.into_iter().collect::<String>());
    }
}
