/* test_libraries.c: tool libraries of CAM systems (Fusion 360 .json and
 * .tools, FreeCAD .fctb/.fctl, CAMotics) and tools from program comments,
 * each written here from the format's public description, against the
 * frepmill JSON table a person writes for the same tools by hand (the
 * mapping worked out in the comments): the same solids, every part's profile
 * compared point by point with lib/tools' distance; the warnings of bounding
 * solids and guesses; the refusals naming file, entry and field. */
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>
#include <zip.h>

#include "test.h"
#include "toolpaths/tooltable/tooltable.h"

static char warnings[16384];
static int nwarnings;

static void on_warning(void *user, const char *msg)
{
    (void)user;
    nwarnings++;
    size_t n = strlen(warnings);
    snprintf(warnings + n, sizeof warnings - n, "%s\n", msg);
}

static const fm_tooltable_options opts = {on_warning, NULL};

static void reset_warnings(void)
{
    warnings[0] = '\0';
    nwarnings = 0;
}

static void table_from(const char *json, fm_tool_table *t)
{
    fm_error err;
    if (fm_tooltable_parse_json(json, strlen(json), "expected.json", t, &err) != FM_OK) {
        fprintf(stderr, "expected table: %s\n", err.message);
        CHECK(0);
    }
}

/* Two parts are the same solid: both there or both absent, equal distance
 * at every point of a grid around them (1e-9 mm). */
static int same_part(const fm_tool_part *a, const fm_tool_part *b)
{
    double rmax = fmax(a->r_max, b->r_max) + 2, zlo = fmin(a->z_lo, b->z_lo) - 2,
           zhi = fmax(a->z_hi, b->z_hi) + 2;
    for (int i = 0; i <= 60; i++)
        for (int j = 0; j <= 120; j++) {
            double r = rmax * i / 60, z = zlo + (zhi - zlo) * j / 120;
            double da = fm_tool_profile_eval(a, NULL, r, z, NULL);
            double db = fm_tool_profile_eval(b, NULL, r, z, NULL);
            if (!(fabs(da - db) <= 1e-9)) {
                fprintf(stderr, "  profiles differ at r %g z %g: %.12g vs %.12g\n", r, z, da, db);
                return 0;
            }
        }
    return 1;
}

/* got has exactly the tools of want, each the same solid (flutes, shank,
 * holder). */
static void check_same_tools(const fm_tool_table *got, const fm_tool_table *want, const char *what)
{
    CHECK(got->count == want->count);
    for (size_t i = 0; i < want->count; i++) {
        const fm_tool_spec *w = &want->tools[i];
        const fm_tool_spec *g = fm_tool_table_find(got, w->number);
        if (!g) {
            fprintf(stderr, "%s: tool %d missing\n", what, w->number);
            CHECK(0);
            continue;
        }
        fm_tool tg, tw;
        fm_error err;
        int ok = fm_tool_build(g, &tg, &err) == FM_OK;
        if (!ok) fprintf(stderr, "%s: T%d: %s\n", what, w->number, err.message);
        CHECK(ok && fm_tool_build(w, &tw, &err) == FM_OK);
        if (!ok) continue;
        int same = g->shape == w->shape && tg.has_shank == tw.has_shank &&
                   tg.has_holder == tw.has_holder && same_part(&tg.flutes, &tw.flutes) &&
                   (!tw.has_shank || same_part(&tg.shank, &tw.shank)) &&
                   (!tw.has_holder || same_part(&tg.holder, &tw.holder));
        if (!same) fprintf(stderr, "%s: T%d is not the expected solid\n", what, w->number);
        CHECK(same);
        CHECK(g->center_cutting == w->center_cutting);
    }
}

/* ----------------------------------------------------------- Fusion 360 */

#define FUS(type, num, geom, extra)                                                              \
    "{\"type\":\"" type "\",\"description\":\"" type " T" #num "\",\"unit\":\"millimeters\","     \
    "\"guid\":\"g" #num "\",\"vendor\":\"Acme\",\"product-id\":\"P" #num "\","                    \
    "\"post-process\":{\"number\":" #num ",\"length-offset\":" #num ",\"diameter-offset\":" #num \
    ",\"comment\":\"\",\"turret\":0},\"geometry\":{" geom "}" extra "}"

static const char *fusion_mm =
    "{\"data\":["
    FUS("flat end mill", 1, "\"DC\":6,\"LCF\":20,\"LB\":40,\"OAL\":60,\"SFDM\":6,\"NOF\":3,\"RE\":0",
        ",\"holder\":{\"type\":\"holder\",\"description\":\"ER20\",\"unit\":\"millimeters\","
        "\"segments\":[{\"height\":10,\"lower-diameter\":20,\"upper-diameter\":20},"
        "{\"height\":15,\"lower-diameter\":25,\"upper-diameter\":32},"
        "{\"height\":20,\"lower-diameter\":40,\"upper-diameter\":40}]},"
        "\"start-values\":{\"presets\":[{\"name\":\"Alu rough\",\"n\":10000,\"v_c\":188.5,"
        "\"v_f\":1500,\"v_f_plunge\":500,\"f_z\":0.05,\"tool-coolant\":\"flood\"}]}") ","
    FUS("ball end mill", 2, "\"DC\":8,\"LCF\":16,\"LB\":35,\"SFDM\":8", "") ","
    FUS("bull nose end mill", 3, "\"DC\":10,\"RE\":1.5,\"LCF\":20,\"LB\":40,\"SFDM\":10", "") ","
    FUS("drill", 4, "\"DC\":5,\"SIG\":118,\"LCF\":30,\"LB\":45,\"SFDM\":5", "") ","
    FUS("spot drill", 5, "\"DC\":10,\"SIG\":90,\"LCF\":12,\"LB\":40,\"SFDM\":10", "") ","
    FUS("chamfer mill", 6, "\"DC\":12,\"TA\":45,\"tip-diameter\":1,\"LCF\":8,\"LB\":40,\"SFDM\":12", "") ","
    FUS("counter sink", 7, "\"DC\":16,\"SIG\":82,\"tip-diameter\":2,\"LCF\":10,\"LB\":40,\"SFDM\":10", "") ","
    FUS("tapered mill", 8, "\"DC\":2,\"TA\":5,\"RE\":1,\"LCF\":15,\"LB\":40,\"SFDM\":6", "") ","
    FUS("dovetail mill", 9, "\"DC\":12,\"TA\":45,\"LCF\":3,\"shoulder-length\":5,\"LB\":30,\"SFDM\":6", "") ","
    FUS("lollipop mill", 10, "\"DC\":6,\"LCF\":6,\"LB\":30,\"SFDM\":3", "") ","
    FUS("face mill", 11, "\"DC\":50,\"LCF\":6,\"LB\":40,\"SFDM\":22,\"TA\":0", "") ","
    FUS("slot mill", 12, "\"DC\":30,\"LCF\":3,\"LB\":25,\"SFDM\":8", "") ","
    FUS("thread mill", 13, "\"DC\":8,\"LCF\":12,\"LB\":35,\"SFDM\":8", "") ","
    FUS("reamer", 14, "\"DC\":6,\"LCF\":20,\"LB\":40", "") ","
    FUS("tap right hand", 15, "\"DC\":6,\"LCF\":15,\"LB\":40", "") ","
    FUS("boring bar", 16, "\"DC\":20,\"LCF\":30,\"LB\":60,\"SFDM\":16", "") ","
    FUS("radius mill", 17, "\"DC\":10,\"LCF\":5,\"LB\":30,\"SFDM\":10", "") ","
    "{\"type\":\"holder\",\"description\":\"BT30 ER20\",\"unit\":\"millimeters\",\"segments\":[]},"
    FUS("probe", 99, "\"DC\":2,\"LCF\":5,\"LB\":50", "")
    "],\"version\":13}";

/* The same tools as frepmill's table, by hand from the mapping: chamfer mill
 * TA 45 per side -> vbit 90 included; counter sink SIG 82 -> vbit 82;
 * dovetail neck DC - 2 LCF tan(TA) = 12 - 6 = 6 up to the shoulder at 5;
 * lollipop neck = SFDM;
 * thread mill, reamer, tap, boring bar, radius mill: the cylinder DC x LCF. */
static const char *fusion_mm_expected =
    "{\"tools\":["
    "{\"number\":1,\"shape\":\"flat\",\"diameter\":6,\"flute_length\":20,\"length\":40,"
    "\"holder\":[{\"diameter\":20,\"length\":10},{\"diameter\":25,\"diameter_top\":32,\"length\":15},"
    "{\"diameter\":40,\"length\":20}]},"
    "{\"number\":2,\"shape\":\"ball\",\"diameter\":8,\"flute_length\":16,\"length\":35},"
    "{\"number\":3,\"shape\":\"bull\",\"diameter\":10,\"corner_radius\":1.5,\"flute_length\":20,\"length\":40},"
    "{\"number\":4,\"shape\":\"drill\",\"diameter\":5,\"point_angle\":118,\"flute_length\":30,\"length\":45},"
    "{\"number\":5,\"shape\":\"drill\",\"diameter\":10,\"point_angle\":90,\"flute_length\":12,\"length\":40},"
    "{\"number\":6,\"shape\":\"vbit\",\"diameter\":12,\"angle\":90,\"tip_diameter\":1,\"flute_length\":8,\"length\":40},"
    "{\"number\":7,\"shape\":\"vbit\",\"diameter\":16,\"angle\":82,\"tip_diameter\":2,\"flute_length\":10,\"length\":40,\"shank_diameter\":10},"
    "{\"number\":8,\"shape\":\"tapered\",\"diameter\":2,\"taper_angle\":5,\"tip_radius\":1,\"flute_length\":15,\"length\":40,\"shank_diameter\":6},"
    "{\"number\":9,\"shape\":\"dovetail\",\"diameter\":12,\"angle\":45,\"neck_diameter\":6,\"flute_length\":5,\"length\":30,\"shank_diameter\":6},"
    "{\"number\":10,\"shape\":\"lollipop\",\"diameter\":6,\"neck_diameter\":3,\"flute_length\":6,\"length\":30,\"shank_diameter\":3},"
    "{\"number\":11,\"shape\":\"flat\",\"diameter\":50,\"flute_length\":6,\"length\":40,\"shank_diameter\":22},"
    "{\"number\":12,\"shape\":\"flat\",\"diameter\":30,\"flute_length\":3,\"length\":25,\"shank_diameter\":8},"
    "{\"number\":13,\"shape\":\"flat\",\"diameter\":8,\"flute_length\":12,\"length\":35},"
    "{\"number\":14,\"shape\":\"flat\",\"diameter\":6,\"flute_length\":20,\"length\":40},"
    "{\"number\":15,\"shape\":\"flat\",\"diameter\":6,\"flute_length\":15,\"length\":40},"
    "{\"number\":16,\"shape\":\"flat\",\"diameter\":20,\"flute_length\":30,\"length\":60,\"shank_diameter\":16},"
    "{\"number\":17,\"shape\":\"flat\",\"diameter\":10,\"flute_length\":5,\"length\":30}]}";

static void test_fusion_json(void)
{
    fm_tool_table got = {0}, want = {0};
    fm_error err;
    reset_warnings();
    CHECK(fm_tooltable_parse(fusion_mm, strlen(fusion_mm), "lib.json", &opts, &got, &err) == FM_OK);
    table_from(fusion_mm_expected, &want);
    check_same_tools(&got, &want, "Fusion mm");
    /* five bounding solids and the probe skipped, each said once */
    CHECK(nwarnings == 6);
    const char *bounded[] = {"thread mill", "reamer", "tap right hand", "boring bar", "radius mill"};
    for (int i = 0; i < 5; i++) CHECK_STR_CONTAINS(warnings, bounded[i]);
    CHECK_STR_CONTAINS(warnings, "T13 \"thread mill T13\"");
    CHECK_STR_CONTAINS(warnings, "bounding solid of revolution");
    CHECK_STR_CONTAINS(warnings, "probe T99\"): skipped: a probe");
    const fm_tool_spec *t1 = fm_tool_table_find(&got, 1);
    CHECK(t1 && !strcmp(t1->comment, "flat end mill T1"));
    CHECK(t1 && t1->flute_count == 3 && t1->length_register == 1 && t1->preset_count == 1);
    CHECK(t1 && t1->diameter_register == 1);
    if (t1 && t1->preset_count == 1) {
        CHECK(!strcmp(t1->presets[0].name, "Alu rough"));
        CHECK_NEAR(t1->presets[0].spindle_rpm, 10000, 0);
        CHECK_NEAR(t1->presets[0].cutting_speed, 188.5, 0);
        CHECK_NEAR(t1->presets[0].feed, 1500, 0);
        CHECK_NEAR(t1->presets[0].plunge_feed, 500, 0);
        CHECK_NEAR(t1->presets[0].feed_per_tooth, 0.05, 0);
    }
    /* the Fusion tools build the solids lib/tools builds from the JSON: the
     * same table must come through the file loader too */
    char path[] = "/tmp/fm_fusion_XXXXXX";
    int fd = mkstemp(path);
    CHECK(fd >= 0 && write(fd, fusion_mm, strlen(fusion_mm)) == (ssize_t)strlen(fusion_mm));
    close(fd);
    fm_tool_table viafile = {0};
    CHECK(fm_tooltable_load(path, &viafile, &err) == FM_OK);
    check_same_tools(&viafile, &want, "Fusion mm from a file");
    unlink(path);
    fm_tool_table_free(&viafile);
    fm_tool_table_free(&got);
    fm_tool_table_free(&want);
}

/* Inches: every length x 25.4 (the holder has its own unit), angles kept,
 * feeds in inch/min and cutting speeds in ft/min. */
static void test_fusion_inch(void)
{
    const char *lib =
        "{\"data\":[{\"type\":\"bull nose end mill\",\"description\":\"1/2 bull\",\"unit\":\"inches\","
        "\"post-process\":{\"number\":7},\"geometry\":{\"DC\":0.5,\"RE\":0.0625,\"LCF\":1,\"LB\":2,"
        "\"SFDM\":0.5},\"holder\":{\"unit\":\"millimeters\",\"segments\":[{\"height\":25.4,"
        "\"lower-diameter\":25.4,\"upper-diameter\":38.1},{\"height\":12.7,\"lower-diameter\":50.8,"
        "\"upper-diameter\":50.8}]},\"start-values\":{\"presets\":[{\"name\":\"steel\",\"n\":3000,"
        "\"v_c\":400,\"v_f\":20}]}},"
        "{\"type\":\"chamfer mill\",\"description\":\"1/4 chamfer\",\"unit\":\"inches\","
        "\"post-process\":{\"number\":8},\"geometry\":{\"DC\":0.25,\"TA\":30,\"LCF\":0.5,\"LB\":1.5}}],"
        "\"version\":2}";
    const char *want_json =
        "{\"units\":\"inch\",\"tools\":[{\"number\":7,\"shape\":\"bull\",\"diameter\":0.5,"
        "\"corner_radius\":0.0625,\"flute_length\":1,\"length\":2,\"holder\":[{\"diameter\":1,"
        "\"diameter_top\":1.5,\"length\":1},{\"diameter\":2,\"length\":0.5}]},"
        "{\"number\":8,\"shape\":\"vbit\",\"diameter\":0.25,\"angle\":60,\"flute_length\":0.5,"
        "\"length\":1.5}]}";
    fm_tool_table got = {0}, want = {0};
    fm_error err;
    CHECK(fm_tooltable_parse(lib, strlen(lib), "inch.json", NULL, &got, &err) == FM_OK);
    table_from(want_json, &want);
    check_same_tools(&got, &want, "Fusion inches");
    const fm_tool_spec *t7 = fm_tool_table_find(&got, 7);
    CHECK(t7 && t7->preset_count == 1);
    if (t7 && t7->preset_count == 1) {
        CHECK_NEAR(t7->presets[0].feed, 20 * 25.4, 1e-9);
        CHECK_NEAR(t7->presets[0].cutting_speed, 400 * 0.3048, 1e-9);
    }
    fm_tool_table_free(&got);
    fm_tool_table_free(&want);
}

/* A holder of 11 segments: the first 7 kept, the top 4 and the 8th become
 * one cylinder as wide as the widest of them and as tall as all (a warning). */
static void test_fusion_long_holder(void)
{
    char lib[4096];
    int n = snprintf(lib, sizeof lib, "{\"data\":[{\"type\":\"flat end mill\",\"unit\":\"millimeters\","
                     "\"post-process\":{\"number\":1},\"geometry\":{\"DC\":6,\"LCF\":10,\"LB\":30},"
                     "\"holder\":{\"segments\":[");
    for (int i = 0; i < 11; i++)
        n += snprintf(lib + n, sizeof lib - n, "%s{\"height\":2,\"lower-diameter\":%d,"
                      "\"upper-diameter\":%d}", i ? "," : "", 10 + i, 10 + i);
    snprintf(lib + n, sizeof lib - n, "]}}]}");
    const char *want_json =
        "{\"tools\":[{\"number\":1,\"shape\":\"flat\",\"diameter\":6,\"flute_length\":10,\"length\":30,"
        "\"holder\":[{\"diameter\":10,\"length\":2},{\"diameter\":11,\"length\":2},{\"diameter\":12,"
        "\"length\":2},{\"diameter\":13,\"length\":2},{\"diameter\":14,\"length\":2},{\"diameter\":15,"
        "\"length\":2},{\"diameter\":16,\"length\":2},{\"diameter\":20,\"length\":8}]}]}";
    fm_tool_table got = {0}, want = {0};
    fm_error err;
    reset_warnings();
    CHECK(fm_tooltable_parse(lib, strlen(lib), "long.json", &opts, &got, &err) == FM_OK);
    table_from(want_json, &want);
    check_same_tools(&got, &want, "Fusion 11-segment holder");
    CHECK(nwarnings == 1);
    CHECK_STR_CONTAINS(warnings, "holder has 11 segments, frepmill keeps 8");
    fm_tool_table_free(&got);
    fm_tool_table_free(&want);
}

static void expect_refusal(const char *text, const char *name, const char *const *fragments)
{
    fm_tool_table t = {0};
    fm_error err;
    fm_status st = fm_tooltable_parse(text, strlen(text), name, NULL, &t, &err);
    CHECK(st == FM_ERR_INPUT || st == FM_ERR_LIMIT || st == FM_ERR_IO);
    CHECK(t.count == 0 && t.tools == NULL);
    CHECK(!strcmp(err.file, name));
    for (; *fragments; fragments++) CHECK_STR_CONTAINS(err.message, *fragments);
}

#define ONE(entry) "{\"data\":[" entry "],\"version\":2}"

static void test_fusion_refusals(void)
{
    expect_refusal(ONE(FUS("form mill", 20, "\"DC\":6,\"LCF\":10,\"LB\":30", "")), "f.json",
                   (const char *[]){"data[0] (T20 \"form mill T20\")", "field \"type\"",
                                    "\"form mill\" is refused", "sketch", NULL});
    expect_refusal(ONE(FUS("turning general", 21, "\"DC\":6,\"LCF\":10,\"LB\":30", "")), "f.json",
                   (const char *[]){"T21", "\"turning general\" is not a milling tool type", NULL});
    expect_refusal(ONE(FUS("flat end mill", 3, "\"LCF\":10,\"LB\":30", "")), "f.json",
                   (const char *[]){"data[0] (T3 \"flat end mill T3\")", "field \"geometry.DC\"",
                                    "missing", NULL});
    expect_refusal(ONE("{\"type\":\"flat end mill\",\"description\":\"6 flat\",\"unit\":\"feet\","
                       "\"post-process\":{\"number\":4},\"geometry\":{\"DC\":6,\"LCF\":10,\"LB\":30}}"),
                   "f.json", (const char *[]){"T4 \"6 flat\"", "field \"unit\"", "\"feet\" is not a unit",
                                              NULL});
    expect_refusal(ONE("{\"type\":\"flat end mill\",\"description\":\"no number\","
                       "\"unit\":\"millimeters\",\"geometry\":{\"DC\":6,\"LCF\":10,\"LB\":30}}"),
                   "f.json", (const char *[]){"data[0] (\"no number\")", "field \"post-process\"", NULL});
    expect_refusal(ONE(FUS("bull nose end mill", 5, "\"DC\":6,\"LCF\":10,\"LB\":30", "")), "f.json",
                   (const char *[]){"T5", "field \"geometry.RE\"", "missing", NULL});
    /* lib/tools' rules, prefixed with the entry */
    expect_refusal(ONE(FUS("flat end mill", 6, "\"DC\":6,\"LCF\":40,\"LB\":30", "")), "f.json",
                   (const char *[]){"data[0] (T6 \"flat end mill T6\")", "flute_length", NULL});
    expect_refusal("{\"data\":[" FUS("flat end mill", 7, "\"DC\":6,\"LCF\":10,\"LB\":30", "") ","
                   FUS("ball end mill", 7, "\"DC\":6,\"LCF\":10,\"LB\":30", "") "]}",
                   "f.json", (const char *[]){"data[1] (T7 \"ball end mill T7\")", "duplicate tool number 7",
                                              NULL});
    expect_refusal(ONE(FUS("flat end mill", 8, "\"DC\":6,\"LCF\":10,\"LB\":30",
                           ",\"holder\":{\"segments\":[{\"height\":5,\"lower-diameter\":20}]}")),
                   "f.json", (const char *[]){"T8", "holder.segments[0].upper-diameter", NULL});
}

/* A zip in a file, entries (name, content) as given. */
static void write_zip(const char *path, const char *const *names, const char *const *texts, int n)
{
    int zerr;
    zip_t *z = zip_open(path, ZIP_CREATE | ZIP_TRUNCATE, &zerr);
    CHECK(z != NULL);
    if (!z) return;
    for (int i = 0; i < n; i++) {
        zip_source_t *s = zip_source_buffer(z, texts[i], strlen(texts[i]), 0);
        CHECK(s && zip_file_add(z, names[i], s, ZIP_FL_ENC_UTF_8) >= 0);
    }
    CHECK(zip_close(z) == 0);
}

static void test_fusion_zip(void)
{
    char path[] = "/tmp/fm_tools_XXXXXX";
    int fd = mkstemp(path);
    CHECK(fd >= 0);
    close(fd);
    fm_tool_table got = {0}, want = {0};
    fm_error err;
    write_zip(path, (const char *[]){"tools.json"}, (const char *[]){fusion_mm}, 1);
    CHECK(fm_tooltable_load(path, &got, &err) == FM_OK);
    table_from(fusion_mm_expected, &want);
    check_same_tools(&got, &want, "Fusion .tools");
    fm_tool_table_free(&got);
    /* refusals: a name that climbs out, no tools.json, not a library */
    write_zip(path, (const char *[]){"tools.json", "../evil.txt"},
              (const char *[]){fusion_mm, "x"}, 2);
    CHECK(fm_tooltable_load(path, &got, &err) == FM_ERR_INPUT);
    CHECK_STR_CONTAINS(err.message, "entry name \"../evil.txt\"");
    CHECK(!strcmp(err.file, path));
    write_zip(path, (const char *[]){"/abs.json", "tools.json"}, (const char *[]){"{}", fusion_mm}, 2);
    CHECK(fm_tooltable_load(path, &got, &err) == FM_ERR_INPUT);
    CHECK_STR_CONTAINS(err.message, "\"/abs.json\"");
    write_zip(path, (const char *[]){"library.json"}, (const char *[]){fusion_mm}, 1);
    CHECK(fm_tooltable_load(path, &got, &err) == FM_ERR_INPUT);
    CHECK_STR_CONTAINS(err.message, "no entry tools.json");
    write_zip(path, (const char *[]){"tools.json"}, (const char *[]){"{\"tools\":[]}"}, 1);
    CHECK(fm_tooltable_load(path, &got, &err) == FM_ERR_INPUT);
    CHECK_STR_CONTAINS(err.message, "not a Fusion tool library");
    /* more entries than the bound */
    const char *names[70], *texts[70];
    char namebuf[70][16];
    for (int i = 0; i < 70; i++) {
        snprintf(namebuf[i], sizeof namebuf[i], "e%d.txt", i);
        names[i] = namebuf[i];
        texts[i] = "x";
    }
    names[0] = "tools.json";
    texts[0] = fusion_mm;
    write_zip(path, names, texts, 70);
    CHECK(fm_tooltable_load(path, &got, &err) == FM_ERR_LIMIT);
    CHECK_STR_CONTAINS(err.message, "too many entries");
    /* a truncated archive */
    write_zip(path, (const char *[]){"tools.json"}, (const char *[]){fusion_mm}, 1);
    struct stat sb;
    CHECK(stat(path, &sb) == 0 && truncate(path, sb.st_size / 2) == 0);
    CHECK(fm_tooltable_load(path, &got, &err) == FM_ERR_INPUT);
    CHECK_STR_CONTAINS(err.message, "Fusion .tools archive");
    unlink(path);
    fm_tool_table_free(&want);
}

/* -------------------------------------------------------------- FreeCAD */

static void put(const char *dir, const char *name, const char *text)
{
    char p[512];
    snprintf(p, sizeof p, "%s/%s", dir, name);
    FILE *f = fopen(p, "w");
    CHECK(f != NULL);
    if (!f) return;
    fputs(text, f);
    fclose(f);
}

#define BIT(name, shape, params)                                                              \
    "{\"version\": 2, \"name\": \"" name "\", \"shape\": \"" shape "\", \"parameter\": {" params \
    "}, \"attribute\": {}}"

static void test_freecad(void)
{
    char root[] = "/tmp/fm_freecad_XXXXXX";
    CHECK(mkdtemp(root) != NULL);
    char bit[600], lib[600];
    snprintf(bit, sizeof bit, "%s/Bit", root);
    snprintf(lib, sizeof lib, "%s/Library", root);
    CHECK(mkdir(bit, 0700) == 0 && mkdir(lib, 0700) == 0);
    put(bit, "endmill.fctb", BIT("6mm Endmill", "endmill.fcstd",
        "\"CuttingEdgeHeight\": \"20.0000 mm\", \"Diameter\": \"6.0000 mm\", \"Length\": \"1.5 in\","
        " \"ShankDiameter\": \"6.0000 mm\""));
    put(bit, "ball.fctb", BIT("8mm Ball End", "ballend.fcstd",
        "\"CuttingEdgeHeight\": \"16 mm\", \"Diameter\": \"8 mm\", \"Length\": \"35 mm\","
        " \"ShankDiameter\": \"8 mm\""));
    put(bit, "bull.fctb", BIT("10mm Bull Nose", "bullnose.fcstd",
        "\"CuttingEdgeHeight\": \"20 mm\", \"Diameter\": \"10 mm\", \"FlatRadius\": \"3.5 mm\","
        " \"Length\": \"40 mm\", \"ShankDiameter\": \"10 mm\""));
    put(bit, "chamfer.fctb", BIT("45 deg chamfer", "chamfer.fcstd",
        "\"CuttingEdgeAngle\": \"90.0000 \xc2\xb0\", \"CuttingEdgeHeight\": \"8 mm\", \"Diameter\": \"12 mm\","
        " \"Length\": \"40 mm\", \"ShankDiameter\": \"12 mm\", \"TipDiameter\": \"1 mm\""));
    put(bit, "vbit.fctb", BIT("60 deg v-bit", "v-bit.fcstd",
        "\"CuttingEdgeAngle\": \"60 \xc2\xb0\", \"CuttingEdgeHeight\": \"6 mm\", \"Diameter\": \"6 mm\","
        " \"Length\": \"20 mm\", \"ShankDiameter\": \"6 mm\", \"TipDiameter\": \"0.2 mm\""));
    put(bit, "drill.fctb", BIT("5mm Drill", "drill.fcstd",
        "\"Diameter\": \"5 mm\", \"Length\": \"45 mm\", \"TipAngle\": \"118 \xc2\xb0\""));
    put(bit, "dovetail.fctb", BIT("12mm dovetail", "dovetail.fcstd",
        "\"CuttingEdgeAngle\": \"45 \xc2\xb0\", \"CuttingEdgeHeight\": \"3 mm\", \"Diameter\": \"12 mm\","
        " \"Length\": \"30 mm\", \"NeckDiameter\": \"6 mm\", \"NeckHeight\": \"2 mm\", \"ShankDiameter\": \"6 mm\""));
    put(bit, "saw.fctb", BIT("30mm slitting saw", "slittingsaw.fcstd",
        "\"BladeThickness\": \"3 mm\", \"CapDiameter\": \"8 mm\", \"CapHeight\": \"3 mm\","
        " \"Diameter\": \"30 mm\", \"Length\": \"25 mm\", \"ShankDiameter\": \"8 mm\""));
    put(bit, "thread.fctb", BIT("M8 thread mill", "thread-mill.fcstd",
        "\"Crest\": \"0.5 mm\", \"CuttingAngle\": \"60 \xc2\xb0\", \"Diameter\": \"8 mm\","
        " \"Length\": \"35 mm\", \"NeckDiameter\": \"5 mm\", \"NeckLength\": \"10 mm\", \"ShankDiameter\": \"8 mm\""));
    put(bit, "probe.fctb", BIT("probe", "probe.fcstd",
        "\"Diameter\": \"2 mm\", \"Length\": \"50 mm\", \"ShaftDiameter\": \"4 mm\""));
    put(lib, "mill.fctl",
        "{\"version\": 1, \"tools\": [{\"nr\": 1, \"path\": \"endmill.fctb\"}, {\"nr\": 2, \"path\": \"ball.fctb\"},"
        " {\"nr\": 3, \"path\": \"bull.fctb\"}, {\"nr\": 6, \"path\": \"chamfer.fctb\"},"
        " {\"nr\": 7, \"path\": \"vbit.fctb\"}, {\"nr\": 4, \"path\": \"drill.fctb\"},"
        " {\"nr\": 9, \"path\": \"dovetail.fctb\"}, {\"nr\": 12, \"path\": \"saw.fctb\"},"
        " {\"nr\": 13, \"path\": \"thread.fctb\"}, {\"nr\": 50, \"path\": \"probe.fctb\"}]}");
    /* by hand: Length 1.5 in = 38.1 mm; bull corner = 5 - 3.5; dovetail
     * angle to the axis 90 - 45, flutes 3 + 2 (cutting edge and neck); the
     * thread mill's head 0.5 + (8 - 5) tan 30 = 2.2320508075688772 high */
    const char *want_json =
        "{\"tools\":["
        "{\"number\":1,\"shape\":\"flat\",\"diameter\":6,\"flute_length\":20,\"length\":38.1},"
        "{\"number\":2,\"shape\":\"ball\",\"diameter\":8,\"flute_length\":16,\"length\":35},"
        "{\"number\":3,\"shape\":\"bull\",\"diameter\":10,\"corner_radius\":1.5,\"flute_length\":20,\"length\":40},"
        "{\"number\":6,\"shape\":\"vbit\",\"diameter\":12,\"angle\":90,\"tip_diameter\":1,\"flute_length\":8,\"length\":40},"
        "{\"number\":7,\"shape\":\"vbit\",\"diameter\":6,\"angle\":60,\"tip_diameter\":0.2,\"flute_length\":6,\"length\":20},"
        "{\"number\":4,\"shape\":\"drill\",\"diameter\":5,\"point_angle\":118,\"flute_length\":45,\"length\":45},"
        "{\"number\":9,\"shape\":\"dovetail\",\"diameter\":12,\"angle\":45,\"neck_diameter\":6,\"flute_length\":5,\"length\":30,\"shank_diameter\":6},"
        "{\"number\":12,\"shape\":\"flat\",\"diameter\":30,\"flute_length\":3,\"length\":25,\"shank_diameter\":8},"
        "{\"number\":13,\"shape\":\"flat\",\"diameter\":8,\"flute_length\":2.2320508075688772,\"length\":35}]}";
    char path[700];
    snprintf(path, sizeof path, "%s/mill.fctl", lib);
    fm_tool_table got = {0}, want = {0};
    fm_error err;
    reset_warnings();
    fm_status st = fm_tooltable_load_with(path, &opts, &got, &err);
    if (st) fprintf(stderr, "%s\n", err.message);
    CHECK(st == FM_OK);
    table_from(want_json, &want);
    check_same_tools(&got, &want, "FreeCAD library");
    CHECK_STR_CONTAINS(warnings, "(T50): skipped: a probe");
    CHECK_STR_CONTAINS(warnings, "thread-mill taken as its bounding solid");
    CHECK(nwarnings == 2);
    CHECK(!strcmp(fm_tool_table_find(&got, 9)->comment, "12mm dovetail"));
    fm_tool_table_free(&got);
    /* one bit alone is tool 1 */
    snprintf(path, sizeof path, "%s/ball.fctb", bit);
    CHECK(fm_tooltable_load(path, &got, &err) == FM_OK);
    CHECK(got.count == 1 && got.tools[0].number == 1 && got.tools[0].shape == FM_TOOL_BALL);
    fm_tool_table_free(&got);
    /* refusals: the bit's file and field; a path that climbs; a library
     * given inline names files; an unknown shape */
    put(bit, "bad.fctb", BIT("broken", "endmill.fcstd", "\"Diameter\": \"6 furlong\", \"Length\": \"40 mm\""));
    put(lib, "bad.fctl", "{\"version\": 1, \"tools\": [{\"nr\": 5, \"path\": \"bad.fctb\"}]}");
    snprintf(path, sizeof path, "%s/bad.fctl", lib);
    CHECK(fm_tooltable_load(path, &got, &err) == FM_ERR_INPUT);
    CHECK_STR_CONTAINS(err.file, "bad.fctb");
    CHECK_STR_CONTAINS(err.message, "bit (T5 \"broken\"): field \"parameter.Diameter\": not a length");
    put(lib, "climb.fctl", "{\"version\": 1, \"tools\": [{\"nr\": 5, \"path\": \"../../etc/passwd\"}]}");
    snprintf(path, sizeof path, "%s/climb.fctl", lib);
    CHECK(fm_tooltable_load(path, &got, &err) == FM_ERR_INPUT);
    CHECK_STR_CONTAINS(err.message, "tools[0] (T5): field \"path\"");
    const char *inline_lib = "{\"version\": 1, \"tools\": [{\"nr\": 1, \"path\": \"endmill.fctb\"}]}";
    CHECK(fm_tooltable_parse(inline_lib, strlen(inline_lib), "job", NULL, &got, &err) == FM_ERR_INPUT);
    CHECK_STR_CONTAINS(err.message, "give it as a file");
    const char *odd = BIT("odd", "corkscrew.fcstd", "\"Diameter\": \"6 mm\", \"Length\": \"40 mm\"");
    CHECK(fm_tooltable_parse(odd, strlen(odd), "odd.fctb", NULL, &got, &err) == FM_ERR_INPUT);
    CHECK_STR_CONTAINS(err.message, "\"corkscrew\" is not a shape FreeCAD ships");
    const char *nodia = BIT("nodia", "endmill.fcstd", "\"CuttingEdgeHeight\": \"6 mm\", \"Length\": \"40 mm\"");
    CHECK(fm_tooltable_parse(nodia, strlen(nodia), "nodia.fctb", NULL, &got, &err) == FM_ERR_INPUT);
    CHECK_STR_CONTAINS(err.message, "T1 \"nodia\"): field \"parameter.Diameter\": missing");
    fm_tool_table_free(&want);
    char cmd[700];
    snprintf(cmd, sizeof cmd, "rm -rf '%s'", root);
    CHECK(system(cmd) == 0);
}

/* ------------------------------------------------------------- CAMotics */

static void test_camotics(void)
{
    const char *project =
        "{\"units\": \"metric\", \"resolution-mode\": \"medium\", \"tools\": {"
        "\"1\": {\"number\": 1, \"units\": \"metric\", \"shape\": \"CYLINDRICAL\", \"length\": 20,"
        " \"diameter\": 6, \"description\": \"6mm flat\"},"
        "\"2\": {\"number\": 2, \"units\": \"metric\", \"shape\": \"BALLNOSE\", \"length\": 16, \"diameter\": 8},"
        "\"3\": {\"number\": 3, \"shape\": \"CONICAL\", \"length\": 10, \"diameter\": 10},"
        "\"4\": {\"number\": 4, \"shape\": \"snubnose\", \"length\": 10, \"diameter\": 6, \"snub_diameter\": 2},"
        "\"5\": {\"number\": 5, \"units\": \"imperial\", \"shape\": \"CYLINDRICAL\", \"length\": 1, \"diameter\": 0.25},"
        "\"6\": {\"number\": 6, \"shape\": \"SPHEROID\", \"length\": 8, \"diameter\": 6}},"
        " \"workpiece\": {\"automatic\": true, \"margin\": 5}, \"files\": [\"part.nc\"]}";
    /* by hand: CAMotics' tool is its cutting part (flutes = length, no
     * shank); the cone's included angle 2 atan(5 / 10); the snub nose a
     * tapered flat tip of 2 mm widening to 6 over 10: atan(2 / 10) per side;
     * the spheroid's bounding cylinder */
    const char *want_json =
        "{\"tools\":["
        "{\"number\":1,\"shape\":\"flat\",\"diameter\":6,\"flute_length\":20,\"length\":20},"
        "{\"number\":2,\"shape\":\"ball\",\"diameter\":8,\"flute_length\":16,\"length\":16},"
        "{\"number\":3,\"shape\":\"vbit\",\"diameter\":10,\"angle\":53.13010235415598,\"flute_length\":10,\"length\":10},"
        "{\"number\":4,\"shape\":\"tapered\",\"diameter\":2,\"taper_angle\":11.309932474020215,\"flute_length\":10,\"length\":10},"
        "{\"number\":5,\"shape\":\"flat\",\"diameter\":6.35,\"flute_length\":25.4,\"length\":25.4},"
        "{\"number\":6,\"shape\":\"flat\",\"diameter\":6,\"flute_length\":8,\"length\":8}]}";
    fm_tool_table got = {0}, want = {0};
    fm_error err;
    reset_warnings();
    fm_status st = fm_tooltable_parse(project, strlen(project), "p.camotics", &opts, &got, &err);
    if (st) fprintf(stderr, "%s\n", err.message);
    CHECK(st == FM_OK);
    table_from(want_json, &want);
    check_same_tools(&got, &want, "CAMotics project");
    CHECK(nwarnings == 1);
    CHECK_STR_CONTAINS(warnings, "SPHEROID taken as its bounding solid");
    CHECK(!strcmp(fm_tool_table_find(&got, 1)->comment, "6mm flat"));
    fm_tool_table_free(&got);
    /* the tool table alone */
    const char *table = "{\"1\": {\"units\": \"mm\", \"shape\": \"CYLINDRICAL\", \"length\": 20, \"diameter\": 6}}";
    CHECK(fm_tooltable_parse(table, strlen(table), "tools.json", NULL, &got, &err) == FM_OK);
    CHECK(got.count == 1 && got.tools[0].number == 1);
    fm_tool_table_free(&got);
    const char *bad = "{\"tools\": {\"2\": {\"shape\": \"TRIANGULAR\", \"length\": 5, \"diameter\": 3,"
                      " \"description\": \"odd\"}}}";
    CHECK(fm_tooltable_parse(bad, strlen(bad), "bad.camotics", NULL, &got, &err) == FM_ERR_INPUT);
    CHECK_STR_CONTAINS(err.message, "tools[\"2\"] (T2 \"odd\"): field \"shape\": \"TRIANGULAR\"");
    const char *unit = "{\"tools\": {\"2\": {\"shape\": \"BALLNOSE\", \"units\": \"furlong\", \"length\": 5,"
                       " \"diameter\": 3}}}";
    CHECK(fm_tooltable_parse(unit, strlen(unit), "bad.camotics", NULL, &got, &err) == FM_ERR_INPUT);
    CHECK_STR_CONTAINS(err.message, "field \"units\"");
    fm_tool_table_free(&want);
}

/* ----------------------------------------------------- program comments */

/* The comments of a program as the interpreter hands them over (the text
 * between parentheses), here found by a plain scan. */
static void feed_comments(fm_tooltable_comments *c, const char *prog)
{
    int line = 1;
    for (const char *p = prog; *p; p++) {
        if (*p == '\n') line++;
        if (*p == '(') {
            const char *e = strchr(p, ')');
            if (!e) break;
            fm_tooltable_comments_add(c, line, p + 1, (size_t)(e - p - 1));
            p = e;
        }
    }
}

static void test_comments(void)
{
    const char *prog =
        "%\n"
        "O1001 (BRACKET)\n"
        "(T1 D=6. CR=0. - ZMIN=-5. - FLAT END MILL)\n"
        "(T2 D=10. CR=1.5 - ZMIN=-40. - BULLNOSE END MILL)\n"
        "(T3 D=12. CR=0. TAPER=45DEG - ZMIN=-1. - CHAMFER MILL)\n"
        "(T4 D=5. CR=0. TAPER=118DEG - ZMIN=-12. - DRILL)\n"
        "(T5 D6 ball nose)\n"
        "(T1 D=8. - a second comment for T1 is not read)\n"
        "(TOOL CHANGE)\n"
        "(T6 without a diameter)\n"
        "T1 M6\n";
    /* by hand: flutes 3 D and at least -ZMIN, stick-out one D more; the
     * chamfer's TAPER per side (45 -> 90 included), the drill's the point */
    const char *want_json =
        "{\"tools\":["
        "{\"number\":1,\"shape\":\"flat\",\"diameter\":6,\"flute_length\":18,\"length\":24},"
        "{\"number\":2,\"shape\":\"bull\",\"diameter\":10,\"corner_radius\":1.5,\"flute_length\":40,\"length\":50},"
        "{\"number\":3,\"shape\":\"vbit\",\"diameter\":12,\"angle\":90,\"flute_length\":36,\"length\":48},"
        "{\"number\":4,\"shape\":\"drill\",\"diameter\":5,\"point_angle\":118,\"flute_length\":15,\"length\":20},"
        "{\"number\":5,\"shape\":\"ball\",\"diameter\":6,\"flute_length\":18,\"length\":24}]}";
    fm_tooltable_comments *c = fm_tooltable_comments_new("part.nc", 0);
    feed_comments(c, prog);
    fm_tool_table got = {0}, want = {0};
    fm_error err;
    reset_warnings();
    CHECK(fm_tooltable_comments_finish(c, &opts, &got, &err) == FM_OK);
    fm_tooltable_comments_free(c);
    table_from(want_json, &want);
    check_same_tools(&got, &want, "program comments");
    CHECK(nwarnings == 5);
    CHECK_STR_CONTAINS(warnings, "part.nc:3: T1 \"FLAT END MILL\" from the program's comment, guessed: "
                                 "flute_length 18 mm (3 x D), length 24 mm (flute length + D), "
                                 "shank_diameter = D, no holder");
    CHECK_STR_CONTAINS(warnings, "part.nc:4: T2 \"BULLNOSE END MILL\"");
    CHECK_STR_CONTAINS(warnings, "flute_length 40 mm (3 x D, the depth ZMIN)");
    CHECK_STR_CONTAINS(warnings, "part.nc:7: T5 \"ball nose\"");
    fm_tool_table_free(&got);
    fm_tool_table_free(&want);
    /* inches (G20): D=.25 is 6.35 mm */
    c = fm_tooltable_comments_new("inch.nc", 1);
    const char *t = "T7 D=.25 CR=0. - ZMIN=-.5 - FLAT END MILL";
    fm_tooltable_comments_add(c, 2, t, strlen(t));
    CHECK(fm_tooltable_comments_finish(c, NULL, &got, &err) == FM_OK);
    CHECK(got.count == 1 && fabs(got.tools[0].diameter - 6.35) < 1e-12 &&
          fabs(got.tools[0].flute_length - 3 * 6.35) < 1e-12);
    fm_tool_table_free(&got);
    fm_tooltable_comments_free(c);
    /* a comment whose tool lib/tools refuses names its line */
    c = fm_tooltable_comments_new("bad.nc", 0);
    t = "T8 D=6. CR=4. - BULLNOSE END MILL";
    fm_tooltable_comments_add(c, 9, t, strlen(t));
    CHECK(fm_tooltable_comments_finish(c, NULL, &got, &err) == FM_ERR_INPUT);
    CHECK(err.line == 9);
    CHECK_STR_CONTAINS(err.message, "line 9 (T8 \"BULLNOSE END MILL\")");
    fm_tooltable_comments_free(c);
    /* no tool comment at all: an empty table */
    c = fm_tooltable_comments_new("none.nc", 0);
    feed_comments(c, "(HELLO)\n(T1 ONLY WORDS)\nG0 X0\n");
    CHECK(fm_tooltable_comments_finish(c, NULL, &got, &err) == FM_OK && got.count == 0);
    fm_tooltable_comments_free(c);
}

/* The loader keeps the old formats: frepmill's JSON errors and .tbl. */
static void test_loader_keeps_old_forms(void)
{
    fm_tool_table got = {0};
    fm_error err;
    const char *bad = "{\"tools\":[{\"number\":1,\"shape\":\"flat\",\"diameter\":6,\"flute_length\":20,"
                      "\"length\":40,\"colour\":1}]}";
    CHECK(fm_tooltable_parse(bad, strlen(bad), "t.json", NULL, &got, &err) == FM_ERR_INPUT);
    CHECK_STR_CONTAINS(err.message, "colour");
    const char *tbl = "T1 P1 D6 Z+12.5 ;6 mm flat\n";
    CHECK(fm_tooltable_parse(tbl, strlen(tbl), "t.tbl", NULL, &got, &err) == FM_OK);
    CHECK(got.count == 1 && got.tools[0].length_offset == 12.5);
    fm_tool_table_free(&got);
}

int main(void)
{
    test_fusion_json();
    test_fusion_inch();
    test_fusion_long_holder();
    test_fusion_refusals();
    test_fusion_zip();
    test_freecad();
    test_camotics();
    test_comments();
    test_loader_keeps_old_forms();
    printf("%d checks, %d failures\n", fm_test_checks, fm_test_failures);
    return fm_test_failures != 0;
}
