pub mod lqr;

// Reserved for the velocity-obstacle expert (thesis eq. 4.1), added by its own task:
// pub mod vo;
