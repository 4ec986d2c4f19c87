/* parse.c: lexer and recursive-descent parser of the HyperFun language
 * into the syntax tree of hf_internal.h. Every error names line:column,
 * what was expected and what was found. The parser is bounded: source
 * size, token count and nesting depth (so deep parentheses cannot
 * overflow the C stack). */
#include "hf/hf_internal.h"

#include <ctype.h>
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

typedef struct hf_parser {
    hf_program *p;
    const char *src;
    size_t len, pos;
    int line, col;     /* of pos */
    /* current token */
    hf_tok tok;
    int tline, tcol;
    size_t tstart, tlen;
    double tnum;
    size_t tokens, depth;
    fm_error *err;
    int failed;
} hf_parser;

static const struct {
    const char *word;
    hf_tok tok;
} keywords[] = {
    {"if", HF_TK_IF},         {"then", HF_TK_THEN},   {"else", HF_TK_ELSE},
    {"endif", HF_TK_ENDIF},   {"while", HF_TK_WHILE}, {"loop", HF_TK_LOOP},
    {"endloop", HF_TK_ENDLOOP}, {"and", HF_TK_AND},   {"or", HF_TK_OR},
    {"not", HF_TK_NOT},       {"array", HF_TK_ARRAY},
};

const char *fm_hf_token_text(hf_tok t)
{
    static const char *const text[HF_TK_COUNT] = {
        "end of input", "a number", "a name", "'('", "')'", "'['", "']'", "'{'", "'}'",
        "','", "';'", "'='", "'<'", "'>'", "'<='", "'>='", "'/='", "'+'", "'-'", "'*'",
        "'/'", "'^'", "'|'", "'&'", "'\\'", "'@'", "'~'", "'if'", "'then'", "'else'",
        "'endif'", "'while'", "'loop'", "'endloop'", "'and'", "'or'", "'not'", "'array'"};
    return t < HF_TK_COUNT ? text[t] : "?";
}

/* ------------------------------------------------------------- errors -- */

static int fail_at(hf_parser *ps, int line, int col, fm_status code, const char *fmt, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 5, 6)))
#endif
    ;

static int fail_at(hf_parser *ps, int line, int col, fm_status code, const char *fmt, ...)
{
    if (ps->failed) return 0;
    ps->failed = 1;
    char msg[sizeof ps->err->message];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(msg, sizeof msg, fmt, ap);
    va_end(ap);
    fm_error_at(ps->err, code, ps->p->source_name, line, col, "%s", msg);
    return 0;
}

/* The current token as the user wrote it, for "found ..." */
static const char *found_text(hf_parser *ps, char *buf, size_t size)
{
    switch (ps->tok) {
    case HF_TK_EOF: return "end of input";
    case HF_TK_NUMBER:
    case HF_TK_NAME: {
        size_t n = ps->tlen < 40 ? ps->tlen : 40;
        snprintf(buf, size, "'%.*s%s'", (int)n, ps->src + ps->tstart, ps->tlen > 40 ? "..." : "");
        return buf;
    }
    default: return fm_hf_token_text(ps->tok);
    }
}

static int expected(hf_parser *ps, const char *what, const char *context)
{
    char buf[64];
    return fail_at(ps, ps->tline, ps->tcol, FM_ERR_INPUT, "expected %s%s%s, found %s", what,
                   context ? " " : "", context ? context : "", found_text(ps, buf, sizeof buf));
}

/* -------------------------------------------------------------- lexer -- */

static void advance_char(hf_parser *ps)
{
    if (ps->src[ps->pos] == '\n') {
        ps->line++;
        ps->col = 1;
    } else {
        ps->col++;
    }
    ps->pos++;
}

static int next_token(hf_parser *ps)
{
    if (ps->failed) return 0;
    /* skip white space and comments */
    for (;;) {
        while (ps->pos < ps->len && isspace((unsigned char)ps->src[ps->pos])) advance_char(ps);
        if (ps->pos + 1 < ps->len && ps->src[ps->pos] == '-' && ps->src[ps->pos + 1] == '-') {
            while (ps->pos < ps->len && ps->src[ps->pos] != '\n') advance_char(ps);
            continue;
        }
        break;
    }
    ps->tline = ps->line;
    ps->tcol = ps->col;
    ps->tstart = ps->pos;
    if (++ps->tokens > ps->p->opt->max_tokens)
        return fail_at(ps, ps->line, ps->col, FM_ERR_LIMIT,
                       "the source has more than %zu tokens (the token budget)",
                       ps->p->opt->max_tokens);
    if (ps->pos >= ps->len) {
        ps->tok = HF_TK_EOF;
        ps->tlen = 0;
        return 1;
    }
    const char *s = ps->src;
    char c = s[ps->pos];
    if (isdigit((unsigned char)c) ||
        (c == '.' && ps->pos + 1 < ps->len && isdigit((unsigned char)s[ps->pos + 1]))) {
        size_t start = ps->pos;
        while (ps->pos < ps->len && isdigit((unsigned char)s[ps->pos])) advance_char(ps);
        if (ps->pos < ps->len && s[ps->pos] == '.') {
            advance_char(ps);
            while (ps->pos < ps->len && isdigit((unsigned char)s[ps->pos])) advance_char(ps);
        }
        if (ps->pos < ps->len && (s[ps->pos] == 'e' || s[ps->pos] == 'E')) {
            size_t save = ps->pos;
            int save_col = ps->col;
            advance_char(ps);
            if (ps->pos < ps->len && (s[ps->pos] == '+' || s[ps->pos] == '-')) advance_char(ps);
            if (ps->pos < ps->len && isdigit((unsigned char)s[ps->pos])) {
                while (ps->pos < ps->len && isdigit((unsigned char)s[ps->pos])) advance_char(ps);
            } else { /* "2e" is the number 2 followed by a name */
                ps->pos = save;
                ps->col = save_col;
            }
        }
        ps->tlen = ps->pos - start;
        if (ps->tlen > 64)
            return fail_at(ps, ps->tline, ps->tcol, FM_ERR_INPUT,
                           "number is too long (%zu characters, at most 64)", ps->tlen);
        char buf[80];
        memcpy(buf, s + start, ps->tlen);
        buf[ps->tlen] = '\0';
        ps->tnum = strtod(buf, NULL);
        ps->tok = HF_TK_NUMBER;
        return 1;
    }
    if (isalpha((unsigned char)c) || c == '_') {
        size_t start = ps->pos;
        while (ps->pos < ps->len &&
               (isalnum((unsigned char)s[ps->pos]) || s[ps->pos] == '_'))
            advance_char(ps);
        ps->tlen = ps->pos - start;
        if (ps->tlen >= FM_HF_NAME_MAX)
            return fail_at(ps, ps->tline, ps->tcol, FM_ERR_INPUT,
                           "name is too long (%zu characters, at most %d)", ps->tlen,
                           FM_HF_NAME_MAX - 1);
        ps->tok = HF_TK_NAME;
        for (size_t i = 0; i < sizeof keywords / sizeof keywords[0]; i++) {
            size_t n = strlen(keywords[i].word);
            if (n != ps->tlen) continue;
            size_t j = 0;
            while (j < n && tolower((unsigned char)s[start + j]) == keywords[i].word[j]) j++;
            if (j == n) {
                ps->tok = keywords[i].tok;
                break;
            }
        }
        return 1;
    }
    char d = ps->pos + 1 < ps->len ? s[ps->pos + 1] : '\0';
    hf_tok t;
    size_t n = 1;
    switch (c) {
    case '(': t = HF_TK_LPAREN; break;
    case ')': t = HF_TK_RPAREN; break;
    case '[': t = HF_TK_LBRACKET; break;
    case ']': t = HF_TK_RBRACKET; break;
    case '{': t = HF_TK_LBRACE; break;
    case '}': t = HF_TK_RBRACE; break;
    case ',': t = HF_TK_COMMA; break;
    case ';': t = HF_TK_SEMI; break;
    case '=': t = HF_TK_EQ; break;
    case '<': t = d == '=' ? (n = 2, HF_TK_LE) : HF_TK_LT; break;
    case '>': t = d == '=' ? (n = 2, HF_TK_GE) : HF_TK_GT; break;
    case '/': t = d == '=' ? (n = 2, HF_TK_NE) : HF_TK_SLASH; break;
    case '+': t = HF_TK_PLUS; break;
    case '-': t = HF_TK_MINUS; break;
    case '*': t = HF_TK_STAR; break;
    case '^': t = HF_TK_CARET; break;
    case '|': t = HF_TK_BAR; break;
    case '&': t = HF_TK_AMP; break;
    case '\\': t = HF_TK_BACKSLASH; break;
    case '@': t = HF_TK_AT; break;
    case '~': t = HF_TK_TILDE; break;
    default:
        if (isprint((unsigned char)c))
            return fail_at(ps, ps->line, ps->col, FM_ERR_INPUT, "unexpected character '%c'", c);
        return fail_at(ps, ps->line, ps->col, FM_ERR_INPUT,
                       "unexpected byte 0x%02x (not a character of the language)",
                       (unsigned)(unsigned char)c);
    }
    for (size_t i = 0; i < n; i++) advance_char(ps);
    ps->tok = t;
    ps->tlen = n;
    return 1;
}

static int expect(hf_parser *ps, hf_tok t, const char *context)
{
    if (ps->tok == t) return next_token(ps);
    return expected(ps, fm_hf_token_text(t), context);
}

/* ------------------------------------------------------------ storage -- */

uint32_t fm_hf_intern(hf_program *p, const char *s, size_t len)
{
    char low[FM_HF_NAME_MAX];
    if (len >= sizeof low) len = sizeof low - 1;
    for (size_t i = 0; i < len; i++) low[i] = (char)tolower((unsigned char)s[i]);
    low[len] = '\0';
    for (size_t i = 1; i < p->name_count; i++)
        if (!strcmp(p->names[i], low)) return (uint32_t)i;
    if (p->name_count == 0) p->name_count = 1;
    if (p->name_count >= p->name_capacity) {
        size_t cap = p->name_capacity ? p->name_capacity * 2 : 64;
        char **names = realloc(p->names, cap * sizeof *names);
        if (!names) return 0;
        p->names = names;
        char **sp = realloc(p->spellings, cap * sizeof *sp);
        if (!sp) return 0;
        p->spellings = sp;
        p->name_capacity = cap;
    }
    char *copy = malloc(len + 1), *spell = malloc(len + 1);
    if (!copy || !spell) {
        free(copy);
        free(spell);
        return 0;
    }
    memcpy(copy, low, len + 1);
    memcpy(spell, s, len);
    spell[len] = '\0';
    p->names[p->name_count] = copy;
    p->spellings[p->name_count] = spell;
    return (uint32_t)p->name_count++;
}

static uint32_t new_node(hf_parser *ps, hf_kind kind, int line, int col)
{
    hf_program *p = ps->p;
    if (ps->failed) return 0;
    if (p->count == 0) p->count = 1;
    if (p->count >= p->capacity) {
        size_t cap = p->capacity ? p->capacity * 2 : 256;
        hf_ast *nodes = realloc(p->nodes, cap * sizeof *nodes);
        if (!nodes) return (uint32_t)fail_at(ps, line, col, FM_ERR_LIMIT, "out of memory parsing");
        p->nodes = nodes;
        p->capacity = cap;
    }
    hf_ast *n = &p->nodes[p->count];
    memset(n, 0, sizeof *n);
    n->kind = (uint8_t)kind;
    n->line = line;
    n->col = col;
    return (uint32_t)p->count++;
}

static uint32_t token_name(hf_parser *ps)
{
    uint32_t id = fm_hf_intern(ps->p, ps->src + ps->tstart, ps->tlen);
    if (!id) fail_at(ps, ps->tline, ps->tcol, FM_ERR_LIMIT, "out of memory parsing");
    return id;
}

static int enter(hf_parser *ps)
{
    if (++ps->depth > ps->p->opt->max_depth)
        return fail_at(ps, ps->tline, ps->tcol, FM_ERR_LIMIT,
                       "nesting is deeper than %zu levels (the depth budget)",
                       ps->p->opt->max_depth);
    return 1;
}

/* ------------------------------------------------------- expressions -- */

static uint32_t parse_expr(hf_parser *ps);

/* Comma-separated expressions up to `close`; returns the first (chained). */
static uint32_t parse_list(hf_parser *ps, hf_tok close, const char *what, int *count)
{
    uint32_t first = 0, last = 0;
    *count = 0;
    if (ps->tok == close) return 0;
    for (;;) {
        uint32_t e = parse_expr(ps);
        if (!e) return 0;
        if (last) ps->p->nodes[last].next = e;
        else first = e;
        last = e;
        ++*count;
        if (ps->tok == HF_TK_COMMA) {
            if (!next_token(ps)) return 0;
            continue;
        }
        if (ps->tok != close) {
            char ctx[80];
            snprintf(ctx, sizeof ctx, "or %s %s", fm_hf_token_text(close), what);
            expected(ps, "','", ctx);
            return 0;
        }
        return first;
    }
}

static uint32_t parse_primary(hf_parser *ps)
{
    int line = ps->tline, col = ps->tcol;
    switch (ps->tok) {
    case HF_TK_NUMBER: {
        uint32_t n = new_node(ps, HF_E_NUM, line, col);
        if (!n) return 0;
        ps->p->nodes[n].num = ps->tnum;
        return next_token(ps) ? n : 0;
    }
    case HF_TK_NAME: {
        uint32_t name = token_name(ps);
        if (!name || !next_token(ps)) return 0;
        if (ps->tok == HF_TK_LPAREN) {
            uint32_t n = new_node(ps, HF_E_CALL, line, col);
            if (!n || !next_token(ps)) return 0;
            int count;
            uint32_t args = parse_list(ps, HF_TK_RPAREN, "after the arguments", &count);
            if (ps->failed || !expect(ps, HF_TK_RPAREN, "after the arguments")) return 0;
            ps->p->nodes[n].name = name;
            ps->p->nodes[n].a = args;
            return n;
        }
        if (ps->tok == HF_TK_LBRACKET) {
            uint32_t n = new_node(ps, HF_E_INDEX, line, col);
            if (!n || !next_token(ps)) return 0;
            uint32_t index = parse_expr(ps);
            if (!index || !expect(ps, HF_TK_RBRACKET, "after the array index")) return 0;
            ps->p->nodes[n].name = name;
            ps->p->nodes[n].a = index;
            return n;
        }
        uint32_t n = new_node(ps, HF_E_NAME, line, col);
        if (n) ps->p->nodes[n].name = name;
        return n;
    }
    case HF_TK_LPAREN: {
        if (!next_token(ps)) return 0;
        uint32_t e = parse_expr(ps);
        if (!e || !expect(ps, HF_TK_RPAREN, "to close '('")) return 0;
        return e;
    }
    case HF_TK_LBRACKET: {
        uint32_t n = new_node(ps, HF_E_ARRAY, line, col);
        if (!n || !next_token(ps)) return 0;
        int count;
        uint32_t items = parse_list(ps, HF_TK_RBRACKET, "after the array items", &count);
        if (ps->failed || !expect(ps, HF_TK_RBRACKET, "after the array items")) return 0;
        if (count == 0) {
            fail_at(ps, line, col, FM_ERR_INPUT, "an array literal needs at least one item");
            return 0;
        }
        ps->p->nodes[n].a = items;
        ps->p->nodes[n].num = count;
        return n;
    }
    default:
        expected(ps, "an expression", NULL);
        return 0;
    }
}

static uint32_t parse_unary(hf_parser *ps)
{
    /* HyperFun binds unary + - ~ tighter than ^: -x^2 is (-x)^2. */
    if (ps->tok == HF_TK_PLUS || ps->tok == HF_TK_MINUS || ps->tok == HF_TK_TILDE) {
        int line = ps->tline, col = ps->tcol;
        hf_tok op = ps->tok;
        if (!enter(ps) || !next_token(ps)) return 0;
        uint32_t a = parse_unary(ps);
        ps->depth--;
        if (!a) return 0;
        uint32_t n = new_node(ps, HF_E_UNARY, line, col);
        if (!n) return 0;
        ps->p->nodes[n].op = (uint8_t)op;
        ps->p->nodes[n].a = a;
        return n;
    }
    if (!enter(ps)) return 0;
    uint32_t e = parse_primary(ps);
    ps->depth--;
    return e;
}

static uint32_t binary(hf_parser *ps, hf_tok op, uint32_t a, uint32_t b, int line, int col)
{
    uint32_t n = new_node(ps, HF_E_BINARY, line, col);
    if (!n) return 0;
    ps->p->nodes[n].op = (uint8_t)op;
    ps->p->nodes[n].a = a;
    ps->p->nodes[n].b = b;
    return n;
}

static int is_level(int level, hf_tok t)
{
    switch (level) {
    case 0: return t == HF_TK_OR;
    case 1: return t == HF_TK_AND;
    case 3: /* HyperFun's additive level holds the set operations too */
        return t == HF_TK_PLUS || t == HF_TK_MINUS || t == HF_TK_BAR || t == HF_TK_AMP ||
               t == HF_TK_BACKSLASH || t == HF_TK_AT;
    case 4: return t == HF_TK_STAR || t == HF_TK_SLASH;
    case 5: return t == HF_TK_CARET;
    default: return 0;
    }
}

static int is_relation(hf_tok t)
{
    return t == HF_TK_EQ || t == HF_TK_NE || t == HF_TK_LT || t == HF_TK_GT || t == HF_TK_LE ||
           t == HF_TK_GE;
}

/* Levels: 0 or, 1 and, 2 relations (a chain a < b <= c means a < b and
 * b <= c, as Pasko's Fig. 6 writes 0 <= x4 <= 1), 3 + - | & \ @, 4 * /,
 * 5 ^ (left-associative, as HyperFun), then unary. All binary levels are
 * left-associative loops, so only parentheses and unary chains recurse. */
static uint32_t parse_level(hf_parser *ps, int level)
{
    if (level > 5) return parse_unary(ps);
    if (level == 2 && ps->tok == HF_TK_NOT) { /* not binds looser than relations */
        int line = ps->tline, col = ps->tcol;
        if (!enter(ps) || !next_token(ps)) return 0;
        uint32_t operand = parse_level(ps, 2);
        ps->depth--;
        if (!operand) return 0;
        uint32_t n = new_node(ps, HF_E_UNARY, line, col);
        if (!n) return 0;
        ps->p->nodes[n].op = HF_TK_NOT;
        ps->p->nodes[n].a = operand;
        return n;
    }
    uint32_t a = parse_level(ps, level + 1);
    if (!a) return 0;
    if (level == 2) {
        uint32_t result = 0, left = a;
        while (is_relation(ps->tok)) {
            int line = ps->tline, col = ps->tcol;
            hf_tok op = ps->tok;
            if (!next_token(ps)) return 0;
            uint32_t right = parse_level(ps, 3);
            if (!right) return 0;
            uint32_t rel = binary(ps, op, left, right, line, col);
            if (!rel) return 0;
            result = result ? binary(ps, HF_TK_AND, result, rel, line, col) : rel;
            if (!result) return 0;
            left = right;
        }
        return result ? result : a;
    }
    while (is_level(level, ps->tok)) {
        int line = ps->tline, col = ps->tcol;
        hf_tok op = ps->tok;
        if (!next_token(ps)) return 0;
        uint32_t b = parse_level(ps, level + 1);
        if (!b) return 0;
        a = binary(ps, op, a, b, line, col);
        if (!a) return 0;
    }
    return a;
}

static uint32_t parse_expr(hf_parser *ps)
{
    if (!enter(ps)) return 0;
    uint32_t e = parse_level(ps, 0);
    ps->depth--;
    return e;
}

/* -------------------------------------------------------- statements -- */

static int ends_block(hf_tok t)
{
    return t == HF_TK_RBRACE || t == HF_TK_EOF || t == HF_TK_ELSE || t == HF_TK_ENDIF ||
           t == HF_TK_ENDLOOP;
}

static uint32_t parse_statements(hf_parser *ps);

static uint32_t parse_statement(hf_parser *ps)
{
    int line = ps->tline, col = ps->tcol;
    switch (ps->tok) {
    case HF_TK_IF: {
        uint32_t n = new_node(ps, HF_S_IF, line, col);
        if (!n || !next_token(ps)) return 0;
        uint32_t cond = parse_expr(ps);
        if (!cond || !expect(ps, HF_TK_THEN, "after the condition of 'if'")) return 0;
        uint32_t then_part = parse_statements(ps), else_part = 0;
        if (ps->failed) return 0;
        if (ps->tok == HF_TK_ELSE) {
            if (!next_token(ps)) return 0;
            else_part = parse_statements(ps);
            if (ps->failed) return 0;
            if (!expect(ps, HF_TK_ENDIF, "to close 'if'")) return 0;
        } else if (ps->tok != HF_TK_ENDIF) {
            expected(ps, "'else' or 'endif'", "to close 'if'");
            return 0;
        } else if (!next_token(ps)) {
            return 0;
        }
        if (!expect(ps, HF_TK_SEMI, "after 'endif'")) return 0;
        hf_ast *s = &ps->p->nodes[n];
        s->a = cond;
        s->b = then_part;
        s->c = else_part;
        return n;
    }
    case HF_TK_WHILE: {
        uint32_t n = new_node(ps, HF_S_WHILE, line, col);
        if (!n || !next_token(ps)) return 0;
        uint32_t cond = parse_expr(ps);
        if (!cond || !expect(ps, HF_TK_LOOP, "after the condition of 'while'")) return 0;
        uint32_t body = parse_statements(ps);
        if (ps->failed) return 0;
        if (!expect(ps, HF_TK_ENDLOOP, "to close 'while'")) return 0;
        if (!expect(ps, HF_TK_SEMI, "after 'endloop'")) return 0;
        ps->p->nodes[n].a = cond;
        ps->p->nodes[n].b = body;
        return n;
    }
    case HF_TK_ARRAY: {
        uint32_t n = new_node(ps, HF_S_ARRAY_DECL, line, col);
        if (!n || !next_token(ps)) return 0;
        uint32_t last = 0;
        for (;;) {
            if (ps->tok != HF_TK_NAME) {
                expected(ps, "an array name", "in 'array' declaration");
                return 0;
            }
            uint32_t d = new_node(ps, HF_E_INDEX, ps->tline, ps->tcol);
            uint32_t name = d ? token_name(ps) : 0;
            if (!name || !next_token(ps)) return 0;
            if (!expect(ps, HF_TK_LBRACKET, "after the array name")) return 0;
            uint32_t size = parse_expr(ps);
            if (!size || !expect(ps, HF_TK_RBRACKET, "after the array size")) return 0;
            ps->p->nodes[d].name = name;
            ps->p->nodes[d].a = size;
            if (last) ps->p->nodes[last].next = d;
            else ps->p->nodes[n].a = d;
            last = d;
            if (ps->tok == HF_TK_COMMA) {
                if (!next_token(ps)) return 0;
                continue;
            }
            break;
        }
        if (!expect(ps, HF_TK_SEMI, "after the array declaration")) return 0;
        return n;
    }
    case HF_TK_NAME: {
        uint32_t name = token_name(ps);
        if (!name || !next_token(ps)) return 0;
        uint32_t n;
        if (ps->tok == HF_TK_LBRACKET) {
            n = new_node(ps, HF_S_ASSIGN_ELEM, line, col);
            if (!n || !next_token(ps)) return 0;
            uint32_t index = parse_expr(ps);
            if (!index || !expect(ps, HF_TK_RBRACKET, "after the array index")) return 0;
            ps->p->nodes[n].a = index;
            if (!expect(ps, HF_TK_EQ, "in assignment")) return 0;
            uint32_t value = parse_expr(ps);
            if (!value) return 0;
            ps->p->nodes[n].b = value;
        } else {
            if (ps->tok != HF_TK_EQ) {
                expected(ps, "'=' or '['", "after a name at the start of a statement");
                return 0;
            }
            n = new_node(ps, HF_S_ASSIGN, line, col);
            if (!n || !next_token(ps)) return 0;
            uint32_t value = parse_expr(ps);
            if (!value) return 0;
            ps->p->nodes[n].a = value;
        }
        ps->p->nodes[n].name = name;
        if (!expect(ps, HF_TK_SEMI, "after assignment")) return 0;
        return n;
    }
    default:
        expected(ps, "a statement (a name, 'if', 'while' or 'array')", NULL);
        return 0;
    }
}

static uint32_t parse_statements(hf_parser *ps)
{
    if (!enter(ps)) return 0;
    uint32_t first = 0, last = 0;
    while (!ends_block(ps->tok)) {
        uint32_t s = parse_statement(ps);
        if (!s) break;
        if (last) ps->p->nodes[last].next = s;
        else first = s;
        last = s;
    }
    ps->depth--;
    return ps->failed ? 0 : first;
}

/* ------------------------------------------------------------ objects -- */

/* name '[' size ']' in an object header; size is a positive integer. */
static int parse_param_array(hf_parser *ps, uint32_t *name, int *dim, const char *role)
{
    if (ps->tok != HF_TK_NAME) {
        char what[80];
        snprintf(what, sizeof what, "the %s array (like %s)", role,
                 !strcmp(role, "coordinate") ? "x[3]" : "a[1]");
        return expected(ps, what, "in the object header");
    }
    *name = token_name(ps);
    if (!*name || !next_token(ps)) return 0;
    if (!expect(ps, HF_TK_LBRACKET, "after the array name in the object header")) return 0;
    if (ps->tok != HF_TK_NUMBER) return expected(ps, "the array size", "in the object header");
    double v = ps->tnum;
    int line = ps->tline, col = ps->tcol;
    if (!(v >= 1 && v <= (!strcmp(role, "coordinate") ? 4 : FM_HF_MAX_PARAMS)) || v != floor(v))
        return fail_at(ps, line, col, FM_ERR_INPUT,
                       "the %s array size must be an integer from 1 to %d, found %g", role,
                       !strcmp(role, "coordinate") ? 4 : FM_HF_MAX_PARAMS, v);
    *dim = (int)v;
    if (!next_token(ps)) return 0;
    return expect(ps, HF_TK_RBRACKET, "after the array size in the object header");
}

static int parse_object(hf_parser *ps)
{
    hf_program *p = ps->p;
    hf_object o;
    memset(&o, 0, sizeof o);
    o.line = ps->tline;
    o.col = ps->tcol;
    if (ps->tok != HF_TK_NAME) return expected(ps, "an object name", "(like 'my_model(x[3], a[1])')");
    o.name = token_name(ps);
    if (!o.name || !next_token(ps)) return 0;
    for (size_t i = 0; i < p->object_count; i++)
        if (p->objects[i].name == o.name)
            return fail_at(ps, o.line, o.col, FM_ERR_INPUT,
                           "object '%s' is defined twice (first at line %d)", p->names[o.name],
                           p->objects[i].line);
    if (!expect(ps, HF_TK_LPAREN, "after the object name")) return 0;
    if (!parse_param_array(ps, &o.x_name, &o.x_dim, "coordinate")) return 0;
    if (ps->tok == HF_TK_COMMA) {
        if (!next_token(ps) || !parse_param_array(ps, &o.a_name, &o.a_dim, "parameter"))
            return 0;
        if (ps->tok == HF_TK_COMMA) { /* HyperFun's attribute array s[]: accepted, ignored */
            if (!next_token(ps) || !parse_param_array(ps, &o.s_name, &o.s_dim, "attribute"))
                return 0;
        }
    }
    if (!expect(ps, HF_TK_RPAREN, "after the object parameters")) return 0;
    if (!expect(ps, HF_TK_LBRACE, "to start the object body")) return 0;
    o.body = parse_statements(ps);
    if (ps->failed) return 0;
    if (ps->tok != HF_TK_RBRACE) return expected(ps, "'}'", "to close the object body");
    if (!next_token(ps)) return 0;
    if (p->object_count == p->object_capacity) {
        size_t cap = p->object_capacity ? p->object_capacity * 2 : 8;
        hf_object *objs = realloc(p->objects, cap * sizeof *objs);
        if (!objs) return fail_at(ps, o.line, o.col, FM_ERR_LIMIT, "out of memory parsing");
        p->objects = objs;
        p->object_capacity = cap;
    }
    p->objects[p->object_count++] = o;
    return 1;
}

fm_status fm_hf_parse(hf_program *p, const char *src, size_t len, int expression_only,
                      uint32_t *root, fm_error *err)
{
    hf_parser ps;
    memset(&ps, 0, sizeof ps);
    ps.p = p;
    ps.src = src;
    ps.len = len;
    ps.line = 1;
    ps.col = 1;
    ps.err = err;
    if (len > p->opt->max_source)
        return fm_error_at(err, FM_ERR_LIMIT, p->source_name, 0, 0,
                           "the source is %zu bytes, more than %zu (the source budget)", len,
                           p->opt->max_source);
    if (memchr(src, '\0', len)) {
        const char *z = memchr(src, '\0', len);
        int line = 1, col = 1;
        for (const char *c = src; c < z; c++) {
            if (*c == '\n') { line++; col = 1; } else col++;
        }
        return fm_error_at(err, FM_ERR_INPUT, p->source_name, line, col,
                           "unexpected NUL byte in the source");
    }
    if (!next_token(&ps)) return err ? err->code : FM_ERR_INPUT;
    if (expression_only) {
        uint32_t e = parse_expr(&ps);
        if (e && ps.tok != HF_TK_EOF) expected(&ps, "end of the expression", NULL);
        if (ps.failed) return err ? err->code : FM_ERR_INPUT;
        *root = e;
        return FM_OK;
    }
    while (ps.tok != HF_TK_EOF)
        if (!parse_object(&ps)) break;
    if (!ps.failed && p->object_count == 0)
        fail_at(&ps, ps.tline, ps.tcol, FM_ERR_INPUT,
                "expected an object (like 'my_model(x[3], a[1]) { ... }'), found end of input");
    return ps.failed ? (err ? err->code : FM_ERR_INPUT) : FM_OK;
}

void fm_hf_program_free(hf_program *p)
{
    if (!p) return;
    for (size_t i = 1; i < p->name_count; i++) {
        free(p->names[i]);
        free(p->spellings[i]);
    }
    free(p->names);
    free(p->spellings);
    free(p->nodes);
    free(p->objects);
    memset(p, 0, sizeof *p);
}

size_t fm_hf_edit_distance(const char *a, const char *b)
{
    size_t n = strlen(a), m = strlen(b);
    if (n > 63 || m > 63) return (size_t)-1;
    size_t row[64];
    for (size_t j = 0; j <= m; j++) row[j] = j;
    for (size_t i = 1; i <= n; i++) {
        size_t diag = row[0];
        row[0] = i;
        for (size_t j = 1; j <= m; j++) {
            size_t up = row[j];
            size_t cost = tolower((unsigned char)a[i - 1]) != tolower((unsigned char)b[j - 1]);
            size_t best = diag + cost;
            if (up + 1 < best) best = up + 1;
            if (row[j - 1] + 1 < best) best = row[j - 1] + 1;
            row[j] = best;
            diag = up;
        }
    }
    return row[m];
}
