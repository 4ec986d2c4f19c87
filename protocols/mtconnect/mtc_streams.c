/* mtc_streams.c: reading an agent's MTConnectStreams document (its answer
 * to current or sample), the other side of mtc_documents.c: each
 * observation (an element with a sequence attribute, at any depth under
 * Streams) handed over in sequence order with its data item's name and id,
 * its timestamp and its text, and the header's nextSequence. libxml2 parses
 * (no network, no entity expansion beyond its defaults and its depth
 * limit); the document's size is bounded before it is read. Live mode's
 * mtconnect:// source (daemon/server/live_source.c) is its user. */
#include <libxml/parser.h>
#include <libxml/tree.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "mtc_internal.h"
#include "mtconnect.h"

typedef struct streams_obs {
    uint64_t seq;
    xmlNodePtr node;
} streams_obs;

typedef struct streams_list {
    streams_obs *items;
    size_t count, cap;
    int out_of_memory;
} streams_list;

static int by_sequence(const void *a, const void *b)
{
    const streams_obs *x = a, *y = b;
    if (x->seq != y->seq) return x->seq < y->seq ? -1 : 1;
    /* the document's order among equal sequences (qsort is not stable) */
    return x->node->line < y->node->line ? -1 : x->node->line > y->node->line;
}

/* Iterative over the tree (libxml2 bounds its depth, but a walk of our own
 * need not rely on that). */
static void collect(xmlNodePtr first, streams_list *list)
{
    xmlNodePtr n = first;
    while (n && !list->out_of_memory) {
        int descend = 0;
        if (n->type == XML_ELEMENT_NODE) {
            xmlChar *seq = xmlGetProp(n, (const xmlChar *)"sequence");
            uint64_t v;
            if (!seq) {
                descend = n->children != NULL;
            } else if (mtc_parse_sequence((const char *)seq, &v) == 0) {
                if (list->count == list->cap) {
                    size_t c = list->cap ? list->cap * 2 : 256;
                    streams_obs *l = realloc(list->items, c * sizeof *l);
                    if (!l) {
                        list->out_of_memory = 1;
                        xmlFree(seq);
                        return;
                    }
                    list->items = l;
                    list->cap = c;
                }
                list->items[list->count].seq = v;
                list->items[list->count].node = n;
                list->count++;
            }
            xmlFree(seq);
        }
        if (descend) {
            n = n->children;
            continue;
        }
        while (n && !n->next && n != first) {
            n = n->parent;
            if (n == first->parent) return;
        }
        if (!n) return;
        n = n->next;
    }
}

int fm_mtc_streams_read(const char *xml, size_t size, fm_mtc_observation_fn fn, void *ctx,
                        uint64_t *next_sequence, char *why, size_t why_size)
{
    if (size > FM_MTC_STREAMS_MAX) {
        snprintf(why, why_size, "the agent's document is %zu bytes, over %zu", size,
                 (size_t)FM_MTC_STREAMS_MAX);
        return -1;
    }
    xmlDocPtr doc = xmlReadMemory(xml, (int)size, "agent.xml", NULL,
                                  XML_PARSE_NONET | XML_PARSE_NOBLANKS | XML_PARSE_NOERROR |
                                      XML_PARSE_NOWARNING);
    if (!doc) {
        const xmlError *e = xmlGetLastError();
        if (e && e->line > 0)
            snprintf(why, why_size, "the agent's document is not XML (line %d, column %d: %s)",
                     e->line, e->int2, e->message ? e->message : "");
        else
            snprintf(why, why_size, "the agent's document is not XML");
        /* libxml2 ends its messages with a newline */
        size_t n = strlen(why);
        while (n && (why[n - 1] == '\n' || why[n - 1] == ' ')) why[--n] = '\0';
        return -1;
    }
    xmlNodePtr root = xmlDocGetRootElement(doc);
    if (!root || strcmp((const char *)root->name, "MTConnectStreams") != 0) {
        snprintf(why, why_size, "the agent answered %.64s, not MTConnectStreams",
                 root ? (const char *)root->name : "nothing");
        xmlFreeDoc(doc);
        return -1;
    }
    for (xmlNodePtr n = root->children; n; n = n->next) {
        if (n->type == XML_ELEMENT_NODE && !strcmp((const char *)n->name, "Header")) {
            xmlChar *v = xmlGetProp(n, (const xmlChar *)"nextSequence");
            uint64_t next;
            if (v && mtc_parse_sequence((const char *)v, &next) == 0) *next_sequence = next;
            xmlFree(v);
        }
    }
    streams_list list = {0};
    if (root->children) collect(root->children, &list);
    if (list.out_of_memory) {
        snprintf(why, why_size, "out of memory reading the agent's document");
        free(list.items);
        xmlFreeDoc(doc);
        return -1;
    }
    if (list.count) qsort(list.items, list.count, sizeof *list.items, by_sequence);
    for (size_t i = 0; i < list.count; i++) {
        xmlNodePtr node = list.items[i].node;
        xmlChar *name = xmlGetProp(node, (const xmlChar *)"name");
        xmlChar *id = xmlGetProp(node, (const xmlChar *)"dataItemId");
        xmlChar *ts = xmlGetProp(node, (const xmlChar *)"timestamp");
        xmlChar *text = xmlNodeGetContent(node);
        fm_mtc_observation o;
        o.sequence = list.items[i].seq;
        o.time = NAN;
        if (ts) fm_mtc_parse_time((const char *)ts, strlen((const char *)ts), &o.time);
        o.name = (const char *)name;
        o.data_item_id = (const char *)id;
        o.value = text ? (const char *)text : "";
        fn(ctx, &o);
        xmlFree(name);
        xmlFree(id);
        xmlFree(ts);
        xmlFree(text);
    }
    free(list.items);
    xmlFreeDoc(doc);
    return 0;
}
