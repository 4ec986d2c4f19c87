/* mtc_documents.c: the device model (one Device: Axes with Linear X/Y/Z,
 * the machine's Rotary axes and the spindle, a Controller with its Path,
 * frepmill's stock data items) and the documents of the REST protocol
 * (MTConnectDevices, MTConnectStreams, MTConnectAssets, MTConnectError),
 * written with libxml2's xmlTextWriter into memory. */
#include <libxml/xmlwriter.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "mtc_internal.h"

/* ------------------------------------------------------------ model -- */

static int add_component(mtc_model *m, const char *element, const char *id, const char *name,
                         int parent)
{
    mtc_component *c = &m->components[m->component_count];
    c->element = element;
    snprintf(c->id, sizeof c->id, "%s", id);
    snprintf(c->name, sizeof c->name, "%s", name);
    c->parent = parent;
    return m->component_count++;
}

static void add_item(mtc_model *m, int component, const char *id, const char *name,
                     mtc_category category, const char *type, const char *sub_type,
                     const char *units, const char *element)
{
    mtc_item *it = &m->items[m->item_count++];
    snprintf(it->id, sizeof it->id, "%s", id);
    snprintf(it->name, sizeof it->name, "%s", name);
    it->category = category;
    it->type = type;
    it->sub_type = sub_type;
    it->units = units;
    it->element = element;
    it->component = component;
}

void mtc_model_build(mtc_model *m, const fm_mtc_device *device)
{
    memset(m, 0, sizeof *m);
    m->device = *device;
    int dev = add_component(m, "Device", "dev", device->name, -1);
    add_item(m, dev, "avail", "avail", MTC_EVENT, "AVAILABILITY", NULL, NULL, "Availability");
    add_item(m, dev, "asset_chg", "asset_chg", MTC_EVENT, "ASSET_CHANGED", NULL, NULL, "AssetChanged");
    add_item(m, dev, "asset_rem", "asset_rem", MTC_EVENT, "ASSET_REMOVED", NULL, NULL, "AssetRemoved");
    int axes = add_component(m, "Axes", "ax", "Axes", dev);
    static const char *const linear[3] = {"X", "Y", "Z"};
    for (int i = 0; i < 3; i++) {
        char id[8], pos[8];
        snprintf(id, sizeof id, "%c", "xyz"[i]);
        snprintf(pos, sizeof pos, "%spos", linear[i]);
        int c = add_component(m, "Linear", id, linear[i], axes);
        add_item(m, c, pos, pos, MTC_SAMPLE, "POSITION", "ACTUAL", "MILLIMETER", "Position");
    }
    for (int i = 0; i < device->rotary_count && i < FM_MTC_MAX_ROTARY; i++) {
        char id[8], name[4], pos[8];
        snprintf(id, sizeof id, "%c", device->rotary[i] - 'A' + 'a');
        snprintf(name, sizeof name, "%c", device->rotary[i]);
        snprintf(pos, sizeof pos, "%cpos", device->rotary[i]);
        int c = add_component(m, "Rotary", id, name, axes);
        add_item(m, c, pos, pos, MTC_SAMPLE, "ANGLE", "ACTUAL", "DEGREE", "Angle");
    }
    int spindle = add_component(m, "Rotary", "sp", "S", axes);
    add_item(m, spindle, "Srpm", "Srpm", MTC_SAMPLE, "ROTARY_VELOCITY", "ACTUAL", "REVOLUTION/MINUTE",
             "RotaryVelocity");
    int ctrl = add_component(m, "Controller", "ctrl", "controller", dev);
    add_item(m, ctrl, "system", "system", MTC_CONDITION, "SYSTEM", NULL, NULL, NULL);
    int path = add_component(m, "Path", "path", "path", ctrl);
    add_item(m, path, "exec", "execution", MTC_EVENT, "EXECUTION", NULL, NULL, "Execution");
    add_item(m, path, "program", "program", MTC_EVENT, "PROGRAM", NULL, NULL, "Program");
    add_item(m, path, "line", "line", MTC_EVENT, "LINE_NUMBER", "ABSOLUTE", NULL, "LineNumber");
    add_item(m, path, "tool", "tool", MTC_EVENT, "TOOL_NUMBER", NULL, NULL, "ToolNumber");
    add_item(m, path, "tool_asset", "tool_asset", MTC_EVENT, "TOOL_ASSET_ID", NULL, NULL, "ToolAssetId");
    add_item(m, path, "path_pos", "path_pos", MTC_SAMPLE, "PATH_POSITION", "ACTUAL", "MILLIMETER_3D",
             "PathPosition");
    add_item(m, path, "motion", "motion", MTC_CONDITION, "MOTION_PROGRAM", NULL, NULL, NULL);
    /* The stock: the workpiece is the standard's Stock (a Material). */
    int materials = add_component(m, "Materials", "mats", "materials", dev);
    int stock = add_component(m, "Stock", "stock", "stock", materials);
    add_item(m, stock, "removed", "removed_volume", MTC_SAMPLE, "VOLUME_SPATIAL", NULL, "CUBIC_MILLIMETER",
             "VolumeSpatial");
    add_item(m, stock, "stock_vol", "stock_volume", MTC_SAMPLE, "VOLUME_SPATIAL", NULL,
             "CUBIC_MILLIMETER", "VolumeSpatial");
    add_item(m, stock, "progress", "progress", MTC_EVENT, "VARIABLE", NULL, "PERCENT", "Variable");
    add_item(m, stock, "uncertain", "uncertain_voxels", MTC_EVENT, "VARIABLE", NULL, "COUNT", "Variable");
}

int mtc_model_find(const mtc_model *m, const char *id)
{
    for (int i = 0; i < m->item_count; i++)
        if (!strcmp(m->items[i].id, id)) return i;
    return -1;
}

static const char *category_name(mtc_category c)
{
    return c == MTC_SAMPLE ? "SAMPLE" : c == MTC_EVENT ? "EVENT" : "CONDITION";
}

static int step_matches_item(const fm_mtc_path_step *s, const mtc_item *it)
{
    if (!s->attr[0]) return 1;
    const char *v = !strcmp(s->attr, "id")         ? it->id
                    : !strcmp(s->attr, "name")     ? it->name
                    : !strcmp(s->attr, "type")     ? it->type
                    : !strcmp(s->attr, "subType")  ? (it->sub_type ? it->sub_type : "")
                    : !strcmp(s->attr, "category") ? category_name(it->category)
                                                   : "";
    return !strcmp(v, s->value);
}

static int step_matches_component(const fm_mtc_path_step *s, const mtc_component *c)
{
    if (strcmp(s->element, "*") && strcmp(s->element, c->element)) return 0;
    if (!s->attr[0]) return 1;
    if (!strcmp(s->attr, "id")) return !strcmp(c->id, s->value);
    if (!strcmp(s->attr, "name")) return !strcmp(c->name, s->value);
    return 0;
}

/* Is the item inside (or on) a component the step matches? */
static int inside(const mtc_model *m, const fm_mtc_path_step *s, int component)
{
    for (int c = component; c >= 0; c = m->components[c].parent)
        if (step_matches_component(s, &m->components[c])) return 1;
    return 0;
}

int mtc_model_select(const mtc_model *m, const fm_mtc_path *path, unsigned char *selected,
                     fm_error *err)
{
    int any = 0;
    memset(selected, 0, (size_t)m->item_count);
    for (int a = 0; a < path->count; a++) {
        const fm_mtc_path_step *cs = &path->alt[a].component, *is = &path->alt[a].item;
        for (int i = 0; i < m->item_count; i++) {
            const mtc_item *it = &m->items[i];
            if (cs->element[0] && !inside(m, cs, it->component)) continue;
            if (is->element[0] && !step_matches_item(is, it)) continue;
            selected[i] = 1;
            any = 1;
        }
    }
    if (!any) {
        fm_error_set_reason(err, FM_ERR_INPUT, "INVALID_XPATH", "the path selects no data item");
        return -1;
    }
    return 0;
}

void mtc_state_apply(mtc_state *s, const mtc_obs *o)
{
    if (o->level == MTC_LEVEL_VALUE) {
        s->last = *o;
        return;
    }
    if (o->level == MTC_LEVEL_UNAVAILABLE || (o->level == FM_MTC_NORMAL && !o->native_code[0])) {
        s->active_count = 0;
        s->last = *o;
        return;
    }
    int at = -1;
    for (int i = 0; i < s->active_count; i++)
        if (!strcmp(s->active[i].native_code, o->native_code)) at = i;
    if (o->level == FM_MTC_NORMAL) {
        if (at >= 0) {
            memmove(&s->active[at], &s->active[at + 1],
                    sizeof s->active[0] * (size_t)(s->active_count - at - 1));
            s->active_count--;
        }
        if (!s->active_count) s->last = *o;
        return;
    }
    if (at < 0) {
        if (s->active_count == MTC_MAX_ACTIVE) {
            memmove(&s->active[0], &s->active[1], sizeof s->active[0] * (MTC_MAX_ACTIVE - 1));
            s->active_count--;
        }
        at = s->active_count++;
    }
    s->active[at] = *o;
}

/* -------------------------------------------------------- documents -- */

void mtc_format_time(double t, char *out, size_t size)
{
    time_t secs = (time_t)floor(t);
    long micros = (long)llround((t - (double)secs) * 1e6);
    if (micros >= 1000000) {
        secs++;
        micros -= 1000000;
    }
    struct tm tm;
    gmtime_r(&secs, &tm);
    snprintf(out, size, "%04d-%02d-%02dT%02d:%02d:%02d.%06ldZ", tm.tm_year + 1900, tm.tm_mon + 1,
             tm.tm_mday, tm.tm_hour, tm.tm_min, tm.tm_sec, micros);
}

typedef struct writer {
    xmlBufferPtr buf;
    xmlTextWriterPtr w;
    int failed;
} writer;

#define X(s) ((const xmlChar *)(s))

static void check(writer *w, int rc)
{
    if (rc < 0) w->failed = 1;
}

static void start(writer *w, const char *name)
{
    check(w, xmlTextWriterStartElement(w->w, X(name)));
}

static void end(writer *w)
{
    check(w, xmlTextWriterEndElement(w->w));
}

static void attr(writer *w, const char *name, const char *value)
{
    check(w, xmlTextWriterWriteAttribute(w->w, X(name), X(value)));
}

static void attr_u64(writer *w, const char *name, uint64_t value)
{
    char text[32];
    snprintf(text, sizeof text, "%llu", (unsigned long long)value);
    attr(w, name, text);
}

static void text(writer *w, const char *value)
{
    check(w, xmlTextWriterWriteString(w->w, X(value)));
}

static void element_text(writer *w, const char *name, const char *value)
{
    start(w, name);
    text(w, value);
    end(w);
}

static int writer_open(writer *w, const char *root, const char *ns, const char *schema)
{
    memset(w, 0, sizeof *w);
    w->buf = xmlBufferCreate();
    if (!w->buf) return -1;
    w->w = xmlNewTextWriterMemory(w->buf, 0);
    if (!w->w) {
        xmlBufferFree(w->buf);
        return -1;
    }
    check(w, xmlTextWriterStartDocument(w->w, NULL, "UTF-8", NULL));
    start(w, root);
    attr(w, "xmlns", ns);
    attr(w, "xmlns:m", ns);
    attr(w, "xmlns:xsi", "http://www.w3.org/2001/XMLSchema-instance");
    char location[256];
    snprintf(location, sizeof location, "%s http://schemas.mtconnect.org/schemas/%s", ns, schema);
    attr(w, "xsi:schemaLocation", location);
    return 0;
}

static char *writer_close(writer *w, size_t *size)
{
    check(w, xmlTextWriterEndDocument(w->w));
    xmlFreeTextWriter(w->w);
    char *out = NULL;
    if (!w->failed) {
        size_t n = (size_t)xmlBufferLength(w->buf);
        out = malloc(n + 1);
        if (out) {
            memcpy(out, xmlBufferContent(w->buf), n);
            out[n] = '\0';
            *size = n;
        }
    }
    xmlBufferFree(w->buf);
    return out;
}

static void header(writer *w, const mtc_header *h, int streams, int assets)
{
    char now[40], model[40];
    mtc_format_time(fm_clock_wall_s(), now, sizeof now);
    mtc_format_time(h->model_time, model, sizeof model);
    start(w, "Header");
    attr(w, "creationTime", now);
    attr(w, "sender", h->sender);
    attr_u64(w, "instanceId", h->instance_id);
    attr(w, "version", FM_MTC_VERSION);
    attr(w, "deviceModelChangeTime", model);
    if (assets) {
        attr_u64(w, "assetBufferSize", FM_MTC_MAX_TOOLS);
        attr_u64(w, "assetCount", (uint64_t)h->asset_count);
    }
    if (assets != 2) attr_u64(w, "bufferSize", h->buffer_size);
    if (streams) {
        attr_u64(w, "nextSequence", h->next);
        attr_u64(w, "firstSequence", h->first);
        attr_u64(w, "lastSequence", h->last);
    }
    end(w);
}

static void write_component(writer *w, const mtc_model *m, int c);

static void write_children(writer *w, const mtc_model *m, int parent)
{
    int any = 0;
    for (int c = 0; c < m->component_count; c++) {
        if (m->components[c].parent != parent) continue;
        if (!any) start(w, "Components");
        any = 1;
        write_component(w, m, c);
    }
    if (any) end(w);
}

static void write_items(writer *w, const mtc_model *m, int component)
{
    int any = 0;
    for (int i = 0; i < m->item_count; i++) {
        const mtc_item *it = &m->items[i];
        if (it->component != component) continue;
        if (!any) start(w, "DataItems");
        any = 1;
        start(w, "DataItem");
        attr(w, "id", it->id);
        attr(w, "name", it->name);
        attr(w, "category", category_name(it->category));
        attr(w, "type", it->type);
        if (it->sub_type) attr(w, "subType", it->sub_type);
        if (it->units) attr(w, "units", it->units);
        end(w);
    }
    if (any) end(w);
}

static void write_component(writer *w, const mtc_model *m, int c)
{
    const mtc_component *comp = &m->components[c];
    start(w, comp->element);
    attr(w, "id", comp->id);
    attr(w, "name", comp->name);
    if (comp->parent < 0) {
        attr(w, "uuid", m->device.uuid);
        start(w, "Description");
        attr(w, "manufacturer", "frepmill");
        attr(w, "model", "frepmill simulator");
        text(w, "the machine frepmilld simulates or follows");
        end(w);
    }
    write_items(w, m, c);
    write_children(w, m, c);
    end(w);
}

char *mtc_write_probe(const mtc_model *m, const mtc_header *h, size_t *size)
{
    writer w;
    if (writer_open(&w, "MTConnectDevices", FM_MTC_NS_DEVICES, "MTConnectDevices_2.7.xsd") != 0)
        return NULL;
    header(&w, h, 0, 1);
    start(&w, "Devices");
    write_component(&w, m, 0);
    end(&w);
    end(&w);
    return writer_close(&w, size);
}

static const char *level_element(int level)
{
    switch (level) {
    case FM_MTC_NORMAL: return "Normal";
    case FM_MTC_WARNING: return "Warning";
    case FM_MTC_FAULT: return "Fault";
    default: return "Unavailable";
    }
}

static void write_observation(writer *w, const mtc_model *m, const mtc_obs *o)
{
    const mtc_item *it = &m->items[o->item];
    char ts[40];
    mtc_format_time(o->time, ts, sizeof ts);
    start(w, it->category == MTC_CONDITION ? level_element(o->level) : it->element);
    attr(w, "dataItemId", it->id);
    attr(w, "timestamp", ts);
    attr_u64(w, "sequence", o->seq);
    attr(w, "name", it->name);
    if (it->category == MTC_CONDITION) {
        attr(w, "type", it->type);
        /* conditionId tells apart the conditions of one data item active
         * at once: the native code (the program line), else the item. */
        if (o->level == FM_MTC_WARNING || o->level == FM_MTC_FAULT)
            attr(w, "conditionId", o->native_code[0] ? o->native_code : it->id);
        if (o->native_code[0]) attr(w, "nativeCode", o->native_code);
        if (o->value[0]) text(w, o->value);
    } else {
        if (it->sub_type) attr(w, "subType", it->sub_type);
        text(w, o->value);
    }
    end(w);
}

char *mtc_write_streams(const mtc_model *m, const mtc_header *h, const mtc_obs *const *obs, size_t count,
                        size_t *size)
{
    writer w;
    if (writer_open(&w, "MTConnectStreams", FM_MTC_NS_STREAMS, "MTConnectStreams_2.7.xsd") != 0)
        return NULL;
    header(&w, h, 1, 0);
    start(&w, "Streams");
    start(&w, "DeviceStream");
    attr(&w, "name", m->device.name);
    attr(&w, "uuid", m->device.uuid);
    static const char *const groups[3] = {"Samples", "Events", "Condition"};
    for (int c = 0; c < m->component_count; c++) {
        int opened = 0;
        for (int g = 0; g < 3; g++) {
            int group_open = 0;
            for (size_t k = 0; k < count; k++) {
                const mtc_item *it = &m->items[obs[k]->item];
                if (it->component != c || (int)it->category != g) continue;
                if (!opened) {
                    start(&w, "ComponentStream");
                    attr(&w, "component", m->components[c].element);
                    attr(&w, "componentId", m->components[c].id);
                    attr(&w, "name", m->components[c].name);
                    opened = 1;
                }
                if (!group_open) start(&w, groups[g]);
                group_open = 1;
                write_observation(&w, m, obs[k]);
            }
            if (group_open) end(&w);
        }
        if (opened) end(&w);
    }
    end(&w);
    end(&w);
    end(&w);
    return writer_close(&w, size);
}

static void measurement(writer *w, const char *element, const char *code, double value)
{
    if (!isfinite(value)) return;
    char v[32];
    snprintf(v, sizeof v, "%.4f", value);
    start(w, element);
    attr(w, "code", code);
    attr(w, "nominal", v);
    attr(w, "units", "MILLIMETER");
    text(w, v);
    end(w);
}

char *mtc_write_assets(const mtc_model *m, const mtc_header *h, const fm_mtc_tool *tools, int count,
                       double now, size_t *size)
{
    writer w;
    if (writer_open(&w, "MTConnectAssets", FM_MTC_NS_ASSETS, "MTConnectAssets_2.7.xsd") != 0) return NULL;
    header(&w, h, 0, 2);
    start(&w, "Assets");
    char ts[40];
    mtc_format_time(now, ts, sizeof ts);
    for (int i = 0; i < count; i++) {
        const fm_mtc_tool *t = &tools[i];
        char id[32], number[24];
        snprintf(id, sizeof id, "T%d", t->number);
        snprintf(number, sizeof number, "%d", t->number);
        start(&w, "CuttingTool");
        attr(&w, "assetId", id);
        attr(&w, "timestamp", ts);
        attr(&w, "deviceUuid", m->device.uuid);
        attr(&w, "toolId", number);
        attr(&w, "serialNumber", number);
        start(&w, "CuttingToolLifeCycle");
        start(&w, "CutterStatus");
        element_text(&w, "Status", "AVAILABLE");
        end(&w);
        element_text(&w, "ProgramToolNumber", number);
        start(&w, "Measurements");
        measurement(&w, "CuttingDiameterMax", "DC", t->diameter);
        measurement(&w, "UsableLengthMax", "LUX", t->flute_length);
        measurement(&w, "OverallToolLength", "OAL", t->overall_length);
        measurement(&w, "ShankDiameter", "DMM", t->shank_diameter);
        end(&w);
        if (isfinite(t->corner_radius) && t->corner_radius > 0) {
            start(&w, "CuttingItems");
            attr(&w, "count", "1");
            start(&w, "CuttingItem");
            attr(&w, "indices", "1");
            start(&w, "Measurements");
            measurement(&w, "CornerRadius", "RE", t->corner_radius);
            end(&w);
            end(&w);
            end(&w);
        }
        end(&w);
        end(&w);
    }
    end(&w);
    end(&w);
    return writer_close(&w, size);
}

static const char *error_element(const char *code)
{
    static const struct {
        const char *code, *element;
    } map[] = {{"QUERY_ERROR", "QueryError"},       {"INVALID_REQUEST", "InvalidRequest"},
               {"INVALID_XPATH", "InvalidXPath"},   {"INVALID_URI", "InvalidURI"},
               {"NO_DEVICE", "NoDevice"},           {"OUT_OF_RANGE", "OutOfRange"},
               {"ASSET_NOT_FOUND", "AssetNotFound"}, {"UNSUPPORTED", "Unsupported"},
               {"TOO_MANY", "TooMany"}};
    for (size_t i = 0; i < sizeof map / sizeof map[0]; i++)
        if (!strcmp(map[i].code, code)) return map[i].element;
    return "InternalError";
}

char *mtc_write_error(const mtc_header *h, const char *code, const char *param, const char *uri,
                      const char *message, size_t *size)
{
    writer w;
    if (writer_open(&w, "MTConnectError", FM_MTC_NS_ERROR, "MTConnectError_2.7.xsd") != 0) return NULL;
    header(&w, h, 0, 0);
    start(&w, "Errors");
    const char *element = error_element(code);
    start(&w, element);
    if (!strcmp(element, "OutOfRange")) {
        start(&w, "QueryParameter");
        attr(&w, "name", param && param[0] ? param : "from");
        end(&w);
    } else if (!strcmp(element, "AssetNotFound")) {
        element_text(&w, "AssetId", param && param[0] ? param : "?");
    }
    element_text(&w, "URI", uri);
    element_text(&w, "ErrorMessage", message);
    end(&w);
    end(&w);
    end(&w);
    return writer_close(&w, size);
}
