//! The condition language: a condition's text parsed, its names and types
//! checked, then evaluated on a run's values.

use super::values::RunValues;

/// Why a condition could not be parsed; `column` counts characters from 1.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum ConditionError {
    /// The text does not follow the grammar at `column`: fix it there.
    #[error("column {column}: expected {expected}, found {found}")]
    Syntax {
        column: usize,
        expected: &'static str,
        found: String,
    },
    /// A name that is not one of the run's values: use one of `known`.
    #[error("column {column}: unknown value `{name}`; known: {}", RunValues::NAMES.join(", "))]
    UnknownName { column: usize, name: String },
    /// A number where a truth value is needed, or the other way round
    /// (e.g. `n_mm and 2`): compare the number with something.
    #[error("column {column}: expected {expected}, found {found}")]
    Type {
        column: usize,
        expected: &'static str,
        found: &'static str,
    },
    /// More than [`MAX_TOKENS`] numbers, names, operators and
    /// parentheses, from `column` on: split the condition.
    #[error(
        "column {column}: a condition has at most {MAX_TOKENS} numbers, names, operators and parentheses"
    )]
    TooLong { column: usize },
}

/// The most tokens a condition may have. Parsing, evaluating and dropping
/// a condition recurse once per nesting level or operator, so a pasted line
/// of thousands of parentheses would otherwise overflow the stack (found
/// with the fuzz target); a condition a person writes has a few dozen.
pub const MAX_TOKENS: usize = 256;

/// A parsed condition; evaluating it cannot fail, only find a value
/// missing (and then it is false).
#[derive(Debug, Clone, PartialEq)]
pub struct Condition {
    text: String,
    expr: Expr,
}

impl Condition {
    pub fn parse(text: &str) -> Result<Self, ConditionError> {
        let tokens = tokenize(text)?;
        let mut parser = Parser { tokens, next: 0 };
        let expr = parser.or()?;
        if let Some(token) = parser.peek() {
            return Err(ConditionError::Syntax {
                column: token.column,
                expected: "an operator or the end",
                found: token.kind.to_string(),
            });
        }
        expect_type(&expr, Type::Bool, 1)?;
        Ok(Self {
            text: text.trim().to_owned(),
            expr,
        })
    }

    /// Whether the condition holds; false if it needs a missing value.
    pub fn holds(&self, values: &RunValues) -> bool {
        matches!(self.expr.eval(values), Some(Value::Bool(true)))
    }

    pub fn text(&self) -> &str {
        &self.text
    }
}

#[derive(Debug, Clone, Copy, PartialEq)]
enum Value {
    Number(f64),
    Bool(bool),
}

#[derive(Debug, Clone, Copy, PartialEq)]
enum Type {
    Number,
    Bool,
}

impl Type {
    fn name(self) -> &'static str {
        match self {
            Type::Number => "a number",
            Type::Bool => "a truth value (a comparison)",
        }
    }
}

#[derive(Debug, Clone, Copy, PartialEq)]
enum BinaryOp {
    Add,
    Sub,
    Mul,
    Div,
    Lt,
    Le,
    Gt,
    Ge,
    Eq,
    Ne,
    And,
    Or,
}

#[derive(Debug, Clone, PartialEq)]
enum Expr {
    Number(f64),
    Name(&'static str),
    Neg(Box<Expr>),
    Not(Box<Expr>),
    Abs(Box<Expr>),
    Binary(BinaryOp, Box<Expr>, Box<Expr>),
}

impl Expr {
    fn ty(&self) -> Type {
        match self {
            Expr::Number(_) | Expr::Name(_) | Expr::Neg(_) | Expr::Abs(_) => Type::Number,
            Expr::Not(_) => Type::Bool,
            Expr::Binary(op, _, _) => match op {
                BinaryOp::Add | BinaryOp::Sub | BinaryOp::Mul | BinaryOp::Div => Type::Number,
                _ => Type::Bool,
            },
        }
    }

    /// `None` when a value it needs is missing.
    fn eval(&self, values: &RunValues) -> Option<Value> {
        let number = |e: &Expr| match e.eval(values)? {
            Value::Number(x) => Some(x),
            Value::Bool(_) => None,
        };
        let truth = |e: &Expr| match e.eval(values)? {
            Value::Bool(b) => Some(b),
            Value::Number(_) => None,
        };
        Some(match self {
            Expr::Number(x) => Value::Number(*x),
            Expr::Name(name) => Value::Number(values.get(name)?),
            Expr::Neg(e) => Value::Number(-number(e)?),
            Expr::Abs(e) => Value::Number(number(e)?.abs()),
            Expr::Not(e) => Value::Bool(!truth(e)?),
            // A missing value on one side of `or` does not hide the other.
            Expr::Binary(BinaryOp::Or, a, b) => {
                Value::Bool(truth(a).unwrap_or(false) || truth(b).unwrap_or(false))
            }
            Expr::Binary(BinaryOp::And, a, b) => Value::Bool(truth(a)? && truth(b)?),
            Expr::Binary(op, a, b) => {
                let (x, y) = (number(a)?, number(b)?);
                match op {
                    BinaryOp::Add => Value::Number(x + y),
                    BinaryOp::Sub => Value::Number(x - y),
                    BinaryOp::Mul => Value::Number(x * y),
                    BinaryOp::Div => Value::Number(x / y),
                    BinaryOp::Lt => Value::Bool(x < y),
                    BinaryOp::Le => Value::Bool(x <= y),
                    BinaryOp::Gt => Value::Bool(x > y),
                    BinaryOp::Ge => Value::Bool(x >= y),
                    BinaryOp::Eq => Value::Bool(x == y),
                    BinaryOp::Ne => Value::Bool(x != y),
                    BinaryOp::And | BinaryOp::Or => unreachable!("handled above"),
                }
            }
        })
    }
}

fn expect_type(expr: &Expr, expected: Type, column: usize) -> Result<(), ConditionError> {
    let found = expr.ty();
    if found == expected {
        Ok(())
    } else {
        Err(ConditionError::Type {
            column,
            expected: expected.name(),
            found: found.name(),
        })
    }
}

#[derive(Debug, Clone, PartialEq)]
enum TokenKind {
    Number(f64),
    Word(String),
    Op(&'static str),
    Open,
    Close,
}

impl std::fmt::Display for TokenKind {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            TokenKind::Number(x) => write!(f, "`{x}`"),
            TokenKind::Word(w) => write!(f, "`{w}`"),
            TokenKind::Op(op) => write!(f, "`{op}`"),
            TokenKind::Open => f.write_str("`(`"),
            TokenKind::Close => f.write_str("`)`"),
        }
    }
}

#[derive(Debug, Clone)]
struct Token {
    kind: TokenKind,
    column: usize,
    /// In characters.
    len: usize,
}

const OPERATORS: [&str; 12] = [
    "<=", ">=", "==", "!=", "&&", "||", "<", ">", "+", "-", "*", "/",
];

fn tokenize(text: &str) -> Result<Vec<Token>, ConditionError> {
    let chars: Vec<char> = text.chars().collect();
    let mut tokens = Vec::new();
    let mut i = 0;
    while i < chars.len() {
        let column = i + 1;
        let c = chars[i];
        if c.is_whitespace() {
            i += 1;
            continue;
        }
        let rest: String = chars[i..chars.len().min(i + 2)].iter().collect();
        let kind = if c == '(' {
            i += 1;
            TokenKind::Open
        } else if c == ')' {
            i += 1;
            TokenKind::Close
        } else if c.is_ascii_digit() || c == '.' {
            let start = i;
            while i < chars.len() && (chars[i].is_ascii_digit() || chars[i] == '.') {
                i += 1;
            }
            // An exponent: 1e-3, 2E4.
            if i < chars.len() && matches!(chars[i], 'e' | 'E') {
                let mut j = i + 1;
                if j < chars.len() && matches!(chars[j], '+' | '-') {
                    j += 1;
                }
                if j < chars.len() && chars[j].is_ascii_digit() {
                    i = j;
                    while i < chars.len() && chars[i].is_ascii_digit() {
                        i += 1;
                    }
                }
            }
            let literal: String = chars[start..i].iter().collect();
            let value = literal.parse().map_err(|_| ConditionError::Syntax {
                column,
                expected: "a number",
                found: format!("`{literal}`"),
            })?;
            TokenKind::Number(value)
        } else if c.is_alphabetic() || c == '_' {
            let start = i;
            while i < chars.len() && (chars[i].is_alphanumeric() || chars[i] == '_') {
                i += 1;
            }
            TokenKind::Word(chars[start..i].iter().collect())
        } else if let Some(op) = OPERATORS.iter().find(|op| rest.starts_with(**op)) {
            i += op.chars().count();
            TokenKind::Op(op)
        } else {
            return Err(ConditionError::Syntax {
                column,
                expected: "a number, a name, an operator or a parenthesis",
                found: format!("`{c}`"),
            });
        };
        if tokens.len() == MAX_TOKENS {
            return Err(ConditionError::TooLong { column });
        }
        tokens.push(Token {
            kind,
            column,
            len: i - (column - 1),
        });
    }
    Ok(tokens)
}

/// Recursive descent, loosest first: or, and, not, comparison, sum,
/// product, unary, atom.
struct Parser {
    tokens: Vec<Token>,
    next: usize,
}

impl Parser {
    fn peek(&self) -> Option<&Token> {
        self.tokens.get(self.next)
    }

    /// Column of the next token, or just past the end.
    fn column(&self) -> usize {
        self.peek().map_or_else(
            || self.tokens.last().map_or(1, |t| t.column + t.len),
            |t| t.column,
        )
    }

    fn found(&self) -> String {
        self.peek()
            .map_or_else(|| "the end".to_owned(), |t| t.kind.to_string())
    }

    fn eat_word(&mut self, word: &str) -> bool {
        let hit = matches!(self.peek(), Some(Token { kind: TokenKind::Word(w), .. }) if w == word);
        self.next += usize::from(hit);
        hit
    }

    fn eat_op(&mut self, ops: &[&'static str]) -> Option<&'static str> {
        match self.peek() {
            Some(Token {
                kind: TokenKind::Op(op),
                ..
            }) if ops.contains(op) => {
                let op = *op;
                self.next += 1;
                Some(op)
            }
            _ => None,
        }
    }

    fn or(&mut self) -> Result<Expr, ConditionError> {
        let mut left = self.and()?;
        loop {
            let column = self.column();
            if !(self.eat_word("or") || self.eat_op(&["||"]).is_some()) {
                return Ok(left);
            }
            let right = self.and()?;
            expect_type(&left, Type::Bool, column)?;
            expect_type(&right, Type::Bool, column)?;
            left = Expr::Binary(BinaryOp::Or, Box::new(left), Box::new(right));
        }
    }

    fn and(&mut self) -> Result<Expr, ConditionError> {
        let mut left = self.not()?;
        loop {
            let column = self.column();
            if !(self.eat_word("and") || self.eat_op(&["&&"]).is_some()) {
                return Ok(left);
            }
            let right = self.not()?;
            expect_type(&left, Type::Bool, column)?;
            expect_type(&right, Type::Bool, column)?;
            left = Expr::Binary(BinaryOp::And, Box::new(left), Box::new(right));
        }
    }

    fn not(&mut self) -> Result<Expr, ConditionError> {
        let column = self.column();
        if self.eat_word("not") {
            let inner = self.not()?;
            expect_type(&inner, Type::Bool, column)?;
            return Ok(Expr::Not(Box::new(inner)));
        }
        self.comparison()
    }

    fn comparison(&mut self) -> Result<Expr, ConditionError> {
        let left = self.sum()?;
        let column = self.column();
        let Some(op) = self.eat_op(&["<", "<=", ">", ">=", "==", "!="]) else {
            return Ok(left);
        };
        let right = self.sum()?;
        expect_type(&left, Type::Number, column)?;
        expect_type(&right, Type::Number, column)?;
        let op = match op {
            "<" => BinaryOp::Lt,
            "<=" => BinaryOp::Le,
            ">" => BinaryOp::Gt,
            ">=" => BinaryOp::Ge,
            "==" => BinaryOp::Eq,
            _ => BinaryOp::Ne,
        };
        Ok(Expr::Binary(op, Box::new(left), Box::new(right)))
    }

    fn sum(&mut self) -> Result<Expr, ConditionError> {
        let mut left = self.product()?;
        loop {
            let column = self.column();
            let Some(op) = self.eat_op(&["+", "-"]) else {
                return Ok(left);
            };
            let right = self.product()?;
            expect_type(&left, Type::Number, column)?;
            expect_type(&right, Type::Number, column)?;
            let op = if op == "+" {
                BinaryOp::Add
            } else {
                BinaryOp::Sub
            };
            left = Expr::Binary(op, Box::new(left), Box::new(right));
        }
    }

    fn product(&mut self) -> Result<Expr, ConditionError> {
        let mut left = self.unary()?;
        loop {
            let column = self.column();
            let Some(op) = self.eat_op(&["*", "/"]) else {
                return Ok(left);
            };
            let right = self.unary()?;
            expect_type(&left, Type::Number, column)?;
            expect_type(&right, Type::Number, column)?;
            let op = if op == "*" {
                BinaryOp::Mul
            } else {
                BinaryOp::Div
            };
            left = Expr::Binary(op, Box::new(left), Box::new(right));
        }
    }

    fn unary(&mut self) -> Result<Expr, ConditionError> {
        let column = self.column();
        if self.eat_op(&["-"]).is_some() {
            let inner = self.unary()?;
            expect_type(&inner, Type::Number, column)?;
            return Ok(Expr::Neg(Box::new(inner)));
        }
        self.atom()
    }

    fn atom(&mut self) -> Result<Expr, ConditionError> {
        let column = self.column();
        let Some(token) = self.peek().cloned() else {
            return Err(ConditionError::Syntax {
                column,
                expected: "a number, a name or `(`",
                found: "the end".into(),
            });
        };
        self.next += 1;
        match token.kind {
            TokenKind::Number(x) => Ok(Expr::Number(x)),
            TokenKind::Open => {
                let inner = self.or()?;
                self.close()?;
                Ok(inner)
            }
            TokenKind::Word(word) if word == "abs" => {
                if !matches!(
                    self.peek(),
                    Some(Token {
                        kind: TokenKind::Open,
                        ..
                    })
                ) {
                    return Err(ConditionError::Syntax {
                        column: self.column(),
                        expected: "`(` after abs",
                        found: self.found(),
                    });
                }
                self.next += 1;
                let inner_column = self.column();
                let inner = self.or()?;
                expect_type(&inner, Type::Number, inner_column)?;
                self.close()?;
                Ok(Expr::Abs(Box::new(inner)))
            }
            TokenKind::Word(word) => RunValues::NAMES
                .iter()
                .find(|name| **name == word)
                .map(|name| Expr::Name(name))
                .ok_or(ConditionError::UnknownName { column, name: word }),
            kind => Err(ConditionError::Syntax {
                column,
                expected: "a number, a name or `(`",
                found: kind.to_string(),
            }),
        }
    }

    fn close(&mut self) -> Result<(), ConditionError> {
        if matches!(
            self.peek(),
            Some(Token {
                kind: TokenKind::Close,
                ..
            })
        ) {
            self.next += 1;
            Ok(())
        } else {
            Err(ConditionError::Syntax {
                column: self.column(),
                expected: "`)`",
                found: self.found(),
            })
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn holds(text: &str, pairs: &[(&str, f64)]) -> bool {
        Condition::parse(text)
            .unwrap()
            .holds(&RunValues::with(pairs))
    }

    #[test]
    fn arithmetic_and_precedence() {
        assert!(holds("1 + 2 * 3 == 7", &[]));
        assert!(holds("(1 + 2) * 3 == 9", &[]));
        assert!(holds("-2 * -3 > 5.5", &[]));
        assert!(holds("10 / 4 == 2.5", &[]));
        assert!(holds("1e-3 < 0.01", &[]));
        assert!(holds("abs(n_mm) > 2", &[("n_mm", -2.5)]));
        assert!(!holds("abs(n_mm) > 2", &[("n_mm", 1.5)]));
    }

    #[test]
    fn and_or_not() {
        let v = [("n_mm", 3.0), ("regrasps", 1.0)];
        assert!(holds("n_mm > 2 and regrasps == 1", &v));
        assert!(!holds("n_mm > 2 and regrasps == 0", &v));
        assert!(holds("n_mm < 0 or regrasps >= 1", &v));
        assert!(holds("not n_mm < 0 && regrasps != 0", &v));
        assert!(holds("n_mm > 5 || abs(n_mm - 4) <= 1", &v));
    }

    #[test]
    fn a_missing_value_makes_its_comparison_false() {
        assert!(!holds("true_n_mm > 0", &[]));
        assert!(!holds("not (true_n_mm > 0)", &[]));
        assert!(holds("true_n_mm > 0 or grasps == 1", &[("grasps", 1.0)]));
    }

    #[test]
    fn a_condition_too_long_to_parse_safely_is_refused_where_it_becomes_so() {
        // Nesting as deep as the limit allows parses (on a test thread's
        // small stack, unoptimised).
        let depth = (MAX_TOKENS - 3) / 2;
        let deepest = format!("{}n_mm > 1{}", "(".repeat(depth), ")".repeat(depth));
        assert!(holds(&deepest, &[("n_mm", 2.0)]));
        // 20 000 nested parentheses overflowed the stack before the limit.
        let deep = format!("{}n_mm > 1{}", "(".repeat(20_000), ")".repeat(20_000));
        assert_eq!(
            Condition::parse(&deep),
            Err(ConditionError::TooLong {
                column: MAX_TOKENS + 1
            })
        );
        let chain = format!("1{} > 0", " + 1".repeat(MAX_TOKENS));
        assert!(matches!(
            Condition::parse(&chain),
            Err(ConditionError::TooLong { .. })
        ));
    }

    #[test]
    fn errors_say_where() {
        let e = Condition::parse("abs(n_mm > 2").unwrap_err();
        assert!(matches!(e, ConditionError::Type { column: 5, .. }), "{e}");
        let e = Condition::parse("abs(n_mm) > ").unwrap_err();
        assert_eq!(
            e,
            ConditionError::Syntax {
                column: 12,
                expected: "a number, a name or `(`",
                found: "the end".into()
            }
        );
        let e = Condition::parse("n_m > 2").unwrap_err();
        assert!(
            matches!(&e, ConditionError::UnknownName { column: 1, name } if name == "n_m"),
            "{e}"
        );
        assert!(e.to_string().contains("n_mm"));
        let e = Condition::parse("n_mm > 2 $ 3").unwrap_err();
        assert!(
            matches!(e, ConditionError::Syntax { column: 10, .. }),
            "{e}"
        );
        let e = Condition::parse("n_mm + 2").unwrap_err();
        assert!(matches!(e, ConditionError::Type { column: 1, .. }), "{e}");
        let e = Condition::parse("(n_mm > 2").unwrap_err();
        assert!(
            matches!(e, ConditionError::Syntax { column: 10, .. }),
            "{e}"
        );
        let e = Condition::parse("n_mm > 2 3").unwrap_err();
        assert!(
            matches!(e, ConditionError::Syntax { column: 10, .. }),
            "{e}"
        );
    }
}
