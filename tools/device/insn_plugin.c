/*
 * A QEMU TCG plugin that counts guest instructions per translation block, and
 * snapshots all counts whenever a block starting at one of the given "mark"
 * addresses runs. With the firmware's empty `caustic_mark_*` functions as marks, the
 * difference of two snapshots is exactly the instructions executed between them,
 * per block (so per function, after symbolisation by profile.py).
 *
 *   -plugin ./insn_plugin.so,out=FILE,mark=0xADDR,mark=0xADDR...
 *
 * Output (FILE, at exit), one line per translated block:
 *   VADDR N_INSNS COUNT_AT_MARK_1 ... COUNT_AT_MARK_M COUNT_AT_EXIT
 * preceded by a header "# marks ADDR_1 ... ADDR_M" (in the order they were hit).
 *
 * Counting is inline (one 64-bit add per block executed), deterministic under TCG,
 * and independent of host speed. A block that an exception leaves early is still
 * counted whole; the firmware takes none while rendering.
 *
 * Written against QEMU's plugin API version 1 (QEMU 7.x, Debian 12's qemu-system-arm);
 * the few declarations it needs are below so that no QEMU headers are required.
 */
#include <inttypes.h>
#include <stdbool.h>
#include <stddef.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* ---- The subset of QEMU's plugin API (include/qemu/qemu-plugin.h, version 1). ---- */
typedef uint64_t qemu_plugin_id_t;
typedef struct {
    const char *target_name;
    struct { int min; int cur; } version;
    bool system_emulation;
    union { struct { int smp_vcpus; int max_vcpus; } system; };
} qemu_info_t;
struct qemu_plugin_tb;
enum qemu_plugin_cb_flags { QEMU_PLUGIN_CB_NO_REGS, QEMU_PLUGIN_CB_R_REGS, QEMU_PLUGIN_CB_RW_REGS };
enum qemu_plugin_op { QEMU_PLUGIN_INLINE_ADD_U64 };
typedef void (*qemu_plugin_udata_cb_t)(qemu_plugin_id_t id, void *userdata);
typedef void (*qemu_plugin_vcpu_udata_cb_t)(unsigned int vcpu_index, void *userdata);
typedef void (*qemu_plugin_vcpu_tb_trans_cb_t)(qemu_plugin_id_t id, struct qemu_plugin_tb *tb);
void qemu_plugin_register_vcpu_tb_trans_cb(qemu_plugin_id_t id, qemu_plugin_vcpu_tb_trans_cb_t cb);
void qemu_plugin_register_vcpu_tb_exec_cb(struct qemu_plugin_tb *tb, qemu_plugin_vcpu_udata_cb_t cb,
                                          enum qemu_plugin_cb_flags flags, void *userdata);
void qemu_plugin_register_vcpu_tb_exec_inline(struct qemu_plugin_tb *tb, enum qemu_plugin_op op,
                                              void *ptr, uint64_t imm);
void qemu_plugin_register_atexit_cb(qemu_plugin_id_t id, qemu_plugin_udata_cb_t cb, void *userdata);
size_t qemu_plugin_tb_n_insns(const struct qemu_plugin_tb *tb);
uint64_t qemu_plugin_tb_vaddr(const struct qemu_plugin_tb *tb);
/* ------------------------------------------------------------------------------- */

__attribute__((visibility("default"))) int qemu_plugin_version = 1;

#define MAX_MARKS 16
#define MAX_HITS 64

struct block {
    uint64_t vaddr;
    uint64_t n_insns;
    uint64_t count;              /* executions, incremented inline */
    uint64_t at_hit[MAX_HITS];   /* `count` at each mark hit */
    struct block *next;
};

static struct block *blocks;
static uint64_t marks[MAX_MARKS];
static int n_marks;
static uint64_t hit_addr[MAX_HITS];
static int n_hits;
static const char *out_path = "insn-profile.txt";

static void on_mark(unsigned int vcpu, void *udata)
{
    (void)vcpu;
    if (n_hits >= MAX_HITS) {
        return;
    }
    /* Whether the mark's own block (a few instructions) is already counted depends
     * on the order QEMU emits callbacks and inline ops: an uncertainty of one block. */
    for (struct block *b = blocks; b; b = b->next) {
        b->at_hit[n_hits] = b->count;
    }
    hit_addr[n_hits++] = ((struct block *)udata)->vaddr;
}

static void on_translate(qemu_plugin_id_t id, struct qemu_plugin_tb *tb)
{
    (void)id;
    struct block *b = calloc(1, sizeof *b);
    if (!b) {
        abort();
    }
    b->vaddr = qemu_plugin_tb_vaddr(tb);
    b->n_insns = qemu_plugin_tb_n_insns(tb);
    b->next = blocks;
    blocks = b;
    for (int i = 0; i < n_marks; i++) {
        if (marks[i] == b->vaddr) {
            qemu_plugin_register_vcpu_tb_exec_cb(tb, on_mark, QEMU_PLUGIN_CB_NO_REGS, b);
        }
    }
    qemu_plugin_register_vcpu_tb_exec_inline(tb, QEMU_PLUGIN_INLINE_ADD_U64, &b->count, 1);
}

static void on_plugin_exit(qemu_plugin_id_t id, void *udata)
{
    (void)id;
    (void)udata;
    FILE *f = fopen(out_path, "w");
    if (!f) {
        perror(out_path);
        return;
    }
    fprintf(f, "# marks");
    for (int i = 0; i < n_hits; i++) {
        fprintf(f, " 0x%" PRIx64, hit_addr[i]);
    }
    fprintf(f, "\n");
    for (struct block *b = blocks; b; b = b->next) {
        if (b->count == 0) {
            continue;
        }
        fprintf(f, "0x%" PRIx64 " %" PRIu64, b->vaddr, b->n_insns);
        for (int i = 0; i < n_hits; i++) {
            fprintf(f, " %" PRIu64, b->at_hit[i]);
        }
        fprintf(f, " %" PRIu64 "\n", b->count);
    }
    fclose(f);
}

__attribute__((visibility("default"))) int qemu_plugin_install(qemu_plugin_id_t id,
                                                               const qemu_info_t *info,
                                                               int argc, char **argv)
{
    (void)info;
    for (int i = 0; i < argc; i++) {
        if (strncmp(argv[i], "out=", 4) == 0) {
            out_path = argv[i] + 4;
        } else if (strncmp(argv[i], "mark=", 5) == 0 && n_marks < MAX_MARKS) {
            /* Thumb function symbols carry bit 0; blocks start at the even address. */
            marks[n_marks++] = strtoull(argv[i] + 5, NULL, 0) & ~(uint64_t)1;
        } else {
            fprintf(stderr, "insn_plugin: unknown argument %s\n", argv[i]);
            return -1;
        }
    }
    qemu_plugin_register_vcpu_tb_trans_cb(id, on_translate);
    qemu_plugin_register_atexit_cb(id, on_plugin_exit, NULL);
    return 0;
}
