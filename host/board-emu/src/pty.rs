//! USART2 on a pseudo-terminal (placeholder; filled in below).
use anyhow::Result;
pub fn serve(_m: &mut crate::emu::Machine<'_>, _fast: bool, _hang: Option<f64>) -> Result<()> {
    anyhow::bail!("--pty: not yet implemented")
}
