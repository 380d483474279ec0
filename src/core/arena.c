/* Arena (bump allocator) for scratch memory with a common lifetime, e.g. one derivation step or
 * one solver call. Blocks come from the context allocator; reset keeps the first block so that a
 * loop that resets each iteration allocates nothing after warm-up. */
#include "core.h"

struct cbm__arena_block {
    cbm__arena_block *next;
    size_t size, used;
    /* payload follows, 16-byte aligned */
};

#define HEADER_SIZE ((sizeof(cbm__arena_block) + 15u) & ~(size_t)15u)

void cbm__arena_init(cbm__arena *a, cbm_context *ctx, size_t block_size)
{
    a->ctx = ctx;
    a->head = NULL;
    a->block_size = block_size ? block_size : 64 * 1024;
}

void *cbm__arena_alloc(cbm__arena *a, size_t size)
{
    size = (size + 15u) & ~(size_t)15u;
    if (size == 0)
        size = 16;
    cbm__arena_block *b = a->head;
    if (!b || b->size - b->used < size) {
        size_t payload = size > a->block_size ? size : a->block_size;
        b = cbm__alloc(a->ctx, HEADER_SIZE + payload);
        if (!b)
            return NULL;
        b->size = payload;
        b->used = 0;
        b->next = a->head;
        a->head = b;
    }
    void *p = (char *)b + HEADER_SIZE + b->used;
    b->used += size;
    return p;
}

void cbm__arena_reset(cbm__arena *a)
{
    cbm__arena_block *b = a->head;
    if (!b)
        return;
    /* keep the oldest block (the last in the list), free the others */
    while (b->next) {
        cbm__arena_block *n = b->next;
        cbm__free(a->ctx, b, HEADER_SIZE + b->size);
        b = n;
    }
    b->used = 0;
    a->head = b;
}

void cbm__arena_destroy(cbm__arena *a)
{
    cbm__arena_block *b = a->head;
    while (b) {
        cbm__arena_block *n = b->next;
        cbm__free(a->ctx, b, HEADER_SIZE + b->size);
        b = n;
    }
    a->head = NULL;
}
