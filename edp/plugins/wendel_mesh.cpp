// wendel_mesh: read a 3D gmsh mesh (ASCII MSH 2) into a FreeFEM mesh3 with the face adjacency built by sorting.
//
// Registered in the FreeFEM language (load "wendel_mesh"; lib/mesh.idp):
//
//   mesh3 Th = wendelLoadMesh3(string file);
//       The mesh gmshload3(file) gives: the same vertices (label 1), tetrahedra and boundary triangles (their
//       labels the physical tags), in the file's order, and the same adjacency, boundary links, boundary
//       orientation, vertex normals and search tree. FreeFEM's own construction (GenericMesh::BuildAdj)
//       matches the faces in a hash table whose hash, the product of the face's vertex numbers times 2^21
//       modulo the vertex count, fills few buckets when that count is even: 77 % of gmshload3's 6.9 s on the
//       step-42 ball at 217k tetrahedra (39,672 vertices; perf, FreeFEM 4.11), on every MPI rank. Here the
//       faces are sorted by their vertex numbers instead. A mesh this does not cover (not ASCII MSH 2, no
//       boundary triangles, a boundary triangle between two tetrahedra, a face of more than two tetrahedra)
//       goes through FreeFEM's own constructor with gmshload3's arguments: the same mesh, at FreeFEM's cost.
//   long wendelMeshAscii2(string file);
//       1 if the file is ASCII MSH 2 (what wendelLoadMesh3 reads; lib/mesh.idp gives gmshload3 the others).
//   long wendelMeshDiff(mesh3 A, mesh3 B);
//       The number of differences between two meshes (counts, vertices, elements, labels, adjacency, boundary
//       links, vertex normals, element of each vertex, measures): 0 when wendelLoadMesh3 gave gmshload3's mesh
//       (tests/test_kernels.py).
#include "ff++.hpp"
#include "AFunction_ext.hpp"

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string>
#include <unordered_map>
#include <vector>

namespace {

struct Face {
    int a, b, c;     // sorted vertex numbers
    int nk;          // 4 * tetrahedron + face
    bool operator<(const Face& o) const
    {
        if (a != o.a) return a < o.a;
        if (b != o.b) return b < o.b;
        if (c != o.c) return c < o.c;
        return nk < o.nk;
    }
    bool same(const Face& o) const { return a == o.a && b == o.b && c == o.c; }
};

// The file into memory; false if it cannot be read.
bool slurp(const std::string& file, std::vector<char>& buf)
{
    FILE* f = std::fopen(file.c_str(), "rb");
    if (!f) return false;
    std::fseek(f, 0, SEEK_END);
    long n = std::ftell(f);
    std::fseek(f, 0, SEEK_SET);
    buf.resize(n + 1);
    size_t got = std::fread(buf.data(), 1, n, f);
    std::fclose(f);
    buf[got] = '\0';
    return (long)got == n;
}

// The position just after the line "$Name" (at the start of a line), or nullptr.
const char* section(const char* text, const char* name)
{
    const size_t len = std::strlen(name);
    for (const char* p = text; (p = std::strstr(p, name)) != nullptr; p += len)
        if ((p == text || p[-1] == '\n') && (p[len] == '\n' || p[len] == '\r')) return p + len;
    return nullptr;
}

void skipLine(const char*& p)
{
    while (*p && *p != '\n') ++p;
    if (*p) ++p;
}

// The arrays of gmshload3's mesh (vertices, tetrahedra, boundary triangles); false when the file is not ASCII
// MSH 2 or a number is missing.
bool parse(const std::string& file, int& nv, int& nt, int& nbe, Vertex3*& v, Tet*& t, Triangle3*& b)
{
    std::vector<char> buf;
    if (!slurp(file, buf)) return false;
    const char* text = buf.data();
    const char* p = section(text, "$MeshFormat");
    if (!p) return false;
    char* e;
    double version = std::strtod(p, &e);
    long ftype = std::strtol(e, &e, 10);
    if (e == p || version < 2.0 || version >= 3.0 || ftype != 0) return false;
    p = section(text, "$Nodes");
    if (!p) return false;
    nv = (int)std::strtol(p, &e, 10);
    p = e;
    if (nv <= 0) return false;
    v = new Vertex3[nv];
    std::vector<int> num(nv);
    long maxNum = 0;
    for (int i = 0; i < nv; ++i) {
        num[i] = (int)std::strtol(p, &e, 10);
        if (e == p) return false;
        p = e;
        double x = std::strtod(p, &e); p = e;
        double y = std::strtod(p, &e); p = e;
        double z = std::strtod(p, &e);
        if (e == p) return false;
        p = e;
        v[i].x = x; v[i].y = y; v[i].z = z; v[i].lab = 1;
        maxNum = std::max(maxNum, (long)num[i]);
    }
    // gmsh node number -> vertex (a vector when the numbers are dense, as gmsh writes them)
    std::vector<int> dense;
    std::unordered_map<int, int> sparse;
    const bool isDense = maxNum <= 4L * nv + 16;
    if (isDense) {
        dense.assign(maxNum + 1, -1);
        for (int i = 0; i < nv; ++i) dense[num[i]] = i;
    }
    else
        for (int i = 0; i < nv; ++i) sparse[num[i]] = i;
    auto vertex = [&](long n) -> int {
        if (isDense) return (n >= 0 && n <= maxNum) ? dense[n] : -1;
        auto it = sparse.find((int)n);
        return it == sparse.end() ? -1 : it->second;
    };
    p = section(text, "$Elements");
    if (!p) return false;
    long ne = std::strtol(p, &e, 10);
    p = e;
    skipLine(p);
    // two passes over the element lines: the counts, then the elements in the file's order
    const char* start = p;
    nt = 0;
    nbe = 0;
    for (int pass = 0; pass < 2; ++pass) {
        p = start;
        int it = 0, ib = 0;
        if (pass == 1) {
            t = new Tet[nt];
            b = new Triangle3[nbe];
        }
        for (long i = 0; i < ne; ++i) {
            std::strtol(p, &e, 10);                       // element number
            if (e == p) return false;
            p = e;
            long type = std::strtol(p, &e, 10); p = e;
            long ntags = std::strtol(p, &e, 10);
            if (e == p) return false;
            p = e;
            long physical = 0;
            for (long j = 0; j < ntags; ++j) {
                long tag = std::strtol(p, &e, 10);
                p = e;
                if (j == 0) physical = tag;
            }
            if (type == 2 || type == 4) {
                const int n = type == 4 ? 4 : 3;
                int iv[4];
                for (int j = 0; j < n; ++j) {
                    long node = std::strtol(p, &e, 10);
                    if (e == p) return false;
                    p = e;
                    iv[j] = vertex(node);
                    if (iv[j] < 0) return false;
                }
                if (pass == 0) (type == 4 ? nt : nbe)++;
                else if (type == 4) t[it++].set(v, iv, (int)physical);
                else b[ib++].set(v, iv, (int)physical);
            }
            skipLine(p);
        }
    }
    return nt > 0;
}

// The adjacency, boundary links and boundary orientation FreeFEM's BuildAdj gives, by sorting the faces; false
// (nothing changed but the arrays it allocated, freed) for a mesh it does not cover.
bool buildAdjacency(Mesh3& Th)
{
    const int nt = Th.nt, nbe = Th.nbe, nea = Mesh3::nea;
    std::vector<Face> faces((size_t)nea * nt);
    for (int k = 0; k < nt; ++k)
        for (int i = 0; i < nea; ++i) {
            int sens;
            SortArray<int, 3> a(Th.itemadj(k, i, &sens));
            faces[(size_t)nea * k + i] = Face{a.v[0], a.v[1], a.v[2], nea * k + i};
        }
    std::sort(faces.begin(), faces.end());
    int* adj = new int[(size_t)nea * nt];
    const size_t nf = faces.size();
    for (size_t q = 0; q < nf;) {
        size_t r = q + 1;
        while (r < nf && faces[r].same(faces[q])) ++r;
        if (r - q > 2) { delete[] adj; return false; }          // a face of more than two tetrahedra
        if (r - q == 2) {
            adj[faces[q].nk] = faces[q + 1].nk;
            adj[faces[q + 1].nk] = faces[q].nk;
        }
        else adj[faces[q].nk] = -1;
        q = r;
    }
    int* head = new int[nbe];
    std::vector<int> flip;
    for (int ke = 0; ke < nbe; ++ke) {
        int sens;
        SortArray<int, 3> a(Th.itembe(ke, &sens));
        const Face key{a.v[0], a.v[1], a.v[2], -1};
        auto it = std::lower_bound(faces.begin(), faces.end(), key);
        if (it == faces.end() || !it->same(key) || adj[it->nk] >= 0) {   // missing, or between two tetrahedra
            delete[] adj;
            delete[] head;
            return false;
        }
        const int nk = it->nk;
        int sk;
        Th.itemadj(nk / nea, nk % nea, &sk);
        if (sk != sens) flip.push_back(ke);                 // BuildAdj turns it to the tetrahedron's face
        head[ke] = nk;
    }
    for (int ke : flip) Th.borderelements[ke].changeOrientation();
    Th.TheAdjacencesLink = adj;
    Th.BoundaryElementHeadLink = head;
    return true;
}

pmesh3 loadMesh3(Stack stack, string* const& file)
{
    int nv = 0, nt = 0, nbe = 0;
    Vertex3* v = nullptr;
    Tet* t = nullptr;
    Triangle3* b = nullptr;
    Mesh3* Th = nullptr;
    if (!parse(*file, nv, nt, nbe, v, t, b)) {
        delete[] v;
        delete[] t;
        delete[] b;
        ExecError(("wendelLoadMesh3: " + *file + " is not an ASCII MSH 2 file with tetrahedra").c_str());
    }
    if (nbe > 0) {
        // Mesh3(nv, nt, nbe, v, t, b, ...) without BuildAdj: the measures, the bounding box, then the rest
        Th = new Mesh3();
        Th->nv = nv; Th->nt = nt; Th->nbe = nbe;
        Th->vertices = v; Th->elements = t; Th->borderelements = b;
        Th->BuildBound();
        if (buildAdjacency(*Th)) {
            Th->Buildbnormalv();
            Th->BuildjElementConteningVertex();
        }
        else {
            Th->vertices = nullptr; Th->elements = nullptr; Th->borderelements = nullptr;
            Th->nv = Th->nt = Th->nbe = 0;
            Th->destroy();
            Th = nullptr;
        }
    }
    // FreeFEM's own construction, with gmshload3's arguments (cleanmesh and rebuilt boundary without
    // boundary triangles; the orientation argument gets gmshload3's precision 1e-6, i.e. 0)
    if (!Th) Th = new Mesh3(nv, nt, nbe, v, t, b, nbe == 0, false, nbe == 0, 0);
    Th->BuildGTree();
    Add2StackOfPtr2FreeRC(stack, Th);
    return Th;
}

long meshAscii2(string* const& file)
{
    FILE* f = std::fopen(file->c_str(), "rb");
    if (!f) return 0;
    char line[256] = "", fmt[256] = "";
    bool ok = std::fgets(line, sizeof line, f) && std::fgets(fmt, sizeof fmt, f);
    std::fclose(f);
    double version = 0;
    int ftype = -1;
    return ok && std::strncmp(line, "$MeshFormat", 11) == 0 && std::sscanf(fmt, "%lf %d", &version, &ftype) == 2
           && version >= 2.0 && version < 3.0 && ftype == 0;
}

long meshDiff(pmesh3 const& pa, pmesh3 const& pb)
{
    const Mesh3 &A = *pa, &B = *pb;
    if (A.nv != B.nv || A.nt != B.nt || A.nbe != B.nbe) return 1 + std::abs(A.nt - B.nt) + std::abs(A.nv - B.nv);
    long d = 0;
    for (int i = 0; i < A.nv; ++i) {
        const Vertex3 &p = A.vertices[i], &q = B.vertices[i];
        d += p.x != q.x || p.y != q.y || p.z != q.z || p.lab != q.lab;
        d += A.ElementConteningVertex[i] != B.ElementConteningVertex[i];
    }
    for (int k = 0; k < A.nt; ++k) {
        d += A[k].lab != B[k].lab;
        for (int j = 0; j < 4; ++j) d += A(A[k][j]) != B(B[k][j]);
        for (int j = 0; j < 4; ++j) d += A.TheAdjacencesLink[4 * k + j] != B.TheAdjacencesLink[4 * k + j];
    }
    for (int k = 0; k < A.nbe; ++k) {
        d += A.be(k).lab != B.be(k).lab;
        for (int j = 0; j < 3; ++j) d += A(A.be(k)[j]) != B(B.be(k)[j]);
        d += A.BoundaryElementHeadLink[k] != B.BoundaryElementHeadLink[k];
    }
    // the boundary vertex normals, bit for bit (FreeFEM 4.11's Buildbnormalv sums zero vectors: NaN)
    for (int i = 0; i < A.nv; ++i) {
        const R3 na = A.vertices[i].Ne(), nb = B.vertices[i].Ne();
        d += std::memcmp(&na, &nb, sizeof na) != 0;
    }
    d += A.mes != B.mes || A.mesb != B.mesb;
    return d;
}

}  // namespace

static void Load_Init()
{
    Global.Add("wendelLoadMesh3", "(", new OneOperator1s_<pmesh3, string*>(loadMesh3));
    Global.Add("wendelMeshAscii2", "(", new OneOperator1_<long, string*>(meshAscii2));
    Global.Add("wendelMeshDiff", "(", new OneOperator2_<long, pmesh3, pmesh3>(meshDiff));
}
LOADFUNC(Load_Init)
