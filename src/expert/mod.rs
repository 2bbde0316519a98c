pub mod lqr;

pub mod vo;
