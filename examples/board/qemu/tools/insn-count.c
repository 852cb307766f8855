/* insn-count: a QEMU TCG plugin that counts the guest instructions
 * executed between marker functions of the board firmware built with
 * `--features measure` (measure_begin, measure_end_{idle,op,mailbox,other}).
 *
 *   gcc -shared -fPIC -O2 -o libinsn-count.so insn-count.c
 *   qemu-system-arm ... -plugin ./libinsn-count.so,begin=0x..,idle=0x..,op=0x..,mailbox=0x..,other=0x..
 *
 * At exit it prints, per kind of firmware pass, how many passes it saw and
 * the minimum, median and maximum of the instructions from the entry of
 * measure_begin to the entry of the end marker.
 *
 * QEMU's plugin API (version 1, QEMU 7.2) is declared here rather than
 * included, since Debian ships no qemu-plugin.h: only the calls used. */
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

typedef uint64_t qemu_plugin_id_t;
typedef struct qemu_info_t qemu_info_t;
struct qemu_plugin_tb;
struct qemu_plugin_insn;
enum qemu_plugin_cb_flags { QEMU_PLUGIN_CB_NO_REGS };
enum qemu_plugin_op { QEMU_PLUGIN_INLINE_ADD_U64 };

void qemu_plugin_register_vcpu_tb_trans_cb(qemu_plugin_id_t id,
    void (*cb)(qemu_plugin_id_t, struct qemu_plugin_tb *));
size_t qemu_plugin_tb_n_insns(const struct qemu_plugin_tb *tb);
struct qemu_plugin_insn *qemu_plugin_tb_get_insn(const struct qemu_plugin_tb *tb, size_t idx);
uint64_t qemu_plugin_insn_vaddr(const struct qemu_plugin_insn *insn);
void qemu_plugin_register_vcpu_insn_exec_inline(struct qemu_plugin_insn *insn,
    enum qemu_plugin_op op, void *ptr, uint64_t imm);
void qemu_plugin_register_vcpu_insn_exec_cb(struct qemu_plugin_insn *insn,
    void (*cb)(unsigned int vcpu_index, void *userdata), enum qemu_plugin_cb_flags flags,
    void *userdata);
void qemu_plugin_register_atexit_cb(qemu_plugin_id_t id,
    void (*cb)(qemu_plugin_id_t id, void *userdata), void *userdata);
void qemu_plugin_outs(const char *string);

__attribute__((visibility("default"))) int qemu_plugin_version = 1;

enum { BEGIN, IDLE, OP, MAILBOX, OTHER, KINDS };
static const char *names[KINDS] = { "begin", "idle", "op", "mailbox", "other" };
static uint64_t marker[KINDS];
static uint64_t count;        /* instructions executed so far */
static uint64_t started;      /* count at measure_begin */
static int open_pass;
#define MAX_PASSES 200000
static uint64_t *samples[KINDS];
static size_t nsamples[KINDS];

static void on_marker(unsigned int vcpu, void *kind_p)
{
    (void)vcpu;
    int kind = (int)(intptr_t)kind_p;
    if (kind == BEGIN) {
        started = count;
        open_pass = 1;
    } else if (open_pass && nsamples[kind] < MAX_PASSES) {
        samples[kind][nsamples[kind]++] = count - started;
        open_pass = 0;
    }
}

static void on_tb(qemu_plugin_id_t id, struct qemu_plugin_tb *tb)
{
    (void)id;
    size_t n = qemu_plugin_tb_n_insns(tb);
    for (size_t i = 0; i < n; i++) {
        struct qemu_plugin_insn *insn = qemu_plugin_tb_get_insn(tb, i);
        uint64_t pc = qemu_plugin_insn_vaddr(insn);
        for (int k = 0; k < KINDS; k++) {
            if (marker[k] && pc == marker[k]) {
                qemu_plugin_register_vcpu_insn_exec_cb(insn, on_marker,
                    QEMU_PLUGIN_CB_NO_REGS, (void *)(intptr_t)k);
            }
        }
        qemu_plugin_register_vcpu_insn_exec_inline(insn, QEMU_PLUGIN_INLINE_ADD_U64, &count, 1);
    }
}

static int cmp(const void *a, const void *b)
{
    uint64_t x = *(const uint64_t *)a, y = *(const uint64_t *)b;
    return x < y ? -1 : x > y;
}

static void on_exit_cb(qemu_plugin_id_t id, void *p)
{
    (void)id; (void)p;
    char line[256];
    snprintf(line, sizeof line, "insn-count: %llu instructions in all\n",
        (unsigned long long)count);
    qemu_plugin_outs(line);
    for (int k = IDLE; k < KINDS; k++) {
        size_t n = nsamples[k];
        if (n == 0) {
            continue;
        }
        qsort(samples[k], n, sizeof(uint64_t), cmp);
        snprintf(line, sizeof line,
            "insn-count: %-8s passes %7zu  instructions min %7llu  median %7llu  max %7llu\n",
            names[k], n, (unsigned long long)samples[k][0],
            (unsigned long long)samples[k][n / 2], (unsigned long long)samples[k][n - 1]);
        qemu_plugin_outs(line);
    }
}

__attribute__((visibility("default")))
int qemu_plugin_install(qemu_plugin_id_t id, const qemu_info_t *info, int argc, char **argv)
{
    (void)info;
    for (int i = 0; i < argc; i++) {
        for (int k = 0; k < KINDS; k++) {
            size_t l = strlen(names[k]);
            if (strncmp(argv[i], names[k], l) == 0 && argv[i][l] == '=') {
                marker[k] = strtoull(argv[i] + l + 1, NULL, 0) & ~1ull;
            }
        }
    }
    for (int k = 0; k < KINDS; k++) {
        samples[k] = calloc(MAX_PASSES, sizeof(uint64_t));
        if (!samples[k]) {
            return -1;
        }
    }
    qemu_plugin_register_vcpu_tb_trans_cb(id, on_tb);
    qemu_plugin_register_atexit_cb(id, on_exit_cb, NULL);
    return 0;
}
