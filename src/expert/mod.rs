pub mod vo;
