pub mod lqr;

pub mod ppo;

pub mod vo;
