//! Teaching tools built on the renderer and sharing its code: "check my lab"
//! ([`check`]), the pixel inspector ([`inspect`]), the guided walkthrough, and the equation
//! sandbox ([`sandbox`]).

pub mod check;
pub mod inspect;
pub mod sandbox;
pub mod walkthrough;
