/* The board functions of the firmware as stubs for the Cortex-M4 link of
 * scripts/footprint.sh: the measured code calls them, they are not part
 * of the measurement. This file is compiled without -ffunction-sections,
 * so its one .text section (the stubs and the entry) is kept whole in
 * every link, the empty baseline's included, and cancels out of the
 * figures. Nothing here runs: the Cortex-M4 build is measured, not
 * executed (the x86-64 harness.c runs the same Rust code). */
#include <stddef.h>
#include <stdint.h>

int32_t fw_init(void);
int32_t fw_poll(uint64_t now_ns);

int32_t spi_read(uint16_t a, uint8_t *b, size_t n) { (void)a; (void)b; (void)n; return 0; }
int32_t spi_write(uint16_t a, const uint8_t *b, size_t n) { (void)a; (void)b; (void)n; return 0; }
void spi_begin(void) {}
void spi_transfer(const uint8_t *o, uint8_t *i, size_t n) { (void)o; (void)i; (void)n; }
int32_t spi_end(void) { return 0; }
uint8_t board_inputs(void) { return 0; }
void board_set_outputs(uint8_t b) { (void)b; }
void stage_set_current(uint8_t s, uint16_t a, uint16_t b, uint16_t c, uint16_t d, uint16_t e, uint16_t f)
{ (void)s; (void)a; (void)b; (void)c; (void)d; (void)e; (void)f; }
void stage_disable(void) {}
uint16_t stage_measured_ma(uint8_t s) { (void)s; return 0; }
uint8_t stage_faults(void) { return 0; }
void stage_step(uint32_t us) { (void)us; }
int32_t nv_read(size_t o, uint8_t *b, size_t n) { (void)o; (void)b; (void)n; return 0; }
int32_t nv_write(size_t o, const uint8_t *b, size_t n) { (void)o; (void)b; (void)n; return 0; }
size_t flash_slot_capacity(void) { return 4096; }
int32_t flash_erase(uint8_t s) { (void)s; return 0; }
int32_t flash_write(uint8_t s, size_t o, const uint8_t *b, size_t n) { (void)s; (void)o; (void)b; (void)n; return 0; }
ptrdiff_t flash_read(uint8_t s, size_t o, uint8_t *b, size_t n) { (void)s; (void)o; (void)b; return (ptrdiff_t)n; }
int32_t flash_state_read(uint8_t c, uint8_t *b, size_t n) { (void)c; (void)b; (void)n; return -1; }
int32_t flash_state_write(uint8_t c, const uint8_t *b, size_t n) { (void)c; (void)b; (void)n; return 0; }
void fw_halt(void) { for (;;) {} }

/* Entry: power-on and the firmware loop, as a board's main would. */
void _start(void)
{
    uint64_t t = 0;
    fw_init();
    for (;;) {
        fw_poll(t);
        t += 1000000;
    }
}
