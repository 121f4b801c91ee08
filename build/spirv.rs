//! Just enough SPIR-V reading for the build's checks: names, struct member offsets, array strides, descriptor
//! bindings (and which of them the shader may write) and specialization-constant IDs.

use std::collections::{BTreeMap, BTreeSet, HashMap, HashSet};

/// What a descriptor binding is, as the shader declares it.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Descriptor {
    Uniform,
    Storage,
    Sampled,
    StorageImage,
    UniformTexel,
    StorageTexel,
}

#[derive(Default)]
pub struct Module {
    pub names: HashMap<u32, String>,
    /// Struct type → its member types.
    pub struct_members: BTreeMap<u32, Vec<u32>>,
    /// Struct type → member → byte offset.
    pub member_offsets: HashMap<u32, HashMap<u32, u32>>,
    /// Array type → stride.
    pub array_strides: HashMap<u32, u32>,
    /// (set, binding) → what it is and its variable's name, for every descriptor the shader declares.
    pub bindings: BTreeMap<(u32, u32), (Descriptor, String)>,
    /// Specialization-constant IDs, with their names.
    pub spec_ids: BTreeMap<u32, String>,
    /// The (set, binding) of every storage buffer, storage image or storage texel buffer the shader may write:
    /// declared without `readonly` (a buffer block some member of which lacks NonWritable, an image without it).
    pub writable: BTreeSet<(u32, u32)>,
    /// The (set, binding) of every descriptor the shader's code writes: a store, an atomic or an image write
    /// through the variable or a pointer into it (a subset of `writable`; what the validation layers'
    /// synchronization validation takes as the dispatch's write, where every other access of a descriptor the
    /// shader uses is a read).
    pub written: BTreeSet<(u32, u32)>,
    /// The push-constant block, if the shader declares one.
    pub push: Option<PushBlock>,
}

/// A shader's push-constant block: its size in bytes, and the name of the struct it holds (a block of one struct
/// member, `layout(push_constant) uniform XBlock { XPush pc; };`) or else the block's own name.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct PushBlock {
    pub name: String,
    pub size: u32,
}

const OP_NAME: u32 = 5;
const OP_TYPE_BOOL: u32 = 20;
const OP_TYPE_INT: u32 = 21;
const OP_TYPE_FLOAT: u32 = 22;
const OP_TYPE_VECTOR: u32 = 23;
const OP_TYPE_MATRIX: u32 = 24;
const OP_CONSTANT: u32 = 43;
const OP_IMAGE_TEXEL_POINTER: u32 = 60;
const OP_LOAD: u32 = 61;
const OP_STORE: u32 = 62;
const OP_COPY_MEMORY: u32 = 63;
const OP_ACCESS_CHAIN: u32 = 65;
const OP_IN_BOUNDS_ACCESS_CHAIN: u32 = 66;
const OP_PTR_ACCESS_CHAIN: u32 = 67;
const OP_COPY_OBJECT: u32 = 83;
const OP_IMAGE_WRITE: u32 = 99;
const OP_ATOMIC_STORE: u32 = 228;
const OP_ATOMIC_FLAG_CLEAR: u32 = 319;
const OP_TYPE_IMAGE: u32 = 25;
const OP_TYPE_SAMPLED_IMAGE: u32 = 27;
const OP_TYPE_ARRAY: u32 = 28;
const OP_TYPE_RUNTIME_ARRAY: u32 = 29;
const OP_TYPE_STRUCT: u32 = 30;
const OP_TYPE_POINTER: u32 = 32;
const OP_VARIABLE: u32 = 59;
const OP_DECORATE: u32 = 71;
const OP_MEMBER_DECORATE: u32 = 72;

const DEC_SPEC_ID: u32 = 1;
const DEC_ARRAY_STRIDE: u32 = 6;
const DEC_NON_WRITABLE: u32 = 24;
const DEC_BINDING: u32 = 33;
const DEC_DESCRIPTOR_SET: u32 = 34;
const DEC_OFFSET: u32 = 35;
const DEC_MATRIX_STRIDE: u32 = 7;

const SC_UNIFORM_CONSTANT: u32 = 0;
const SC_UNIFORM: u32 = 2;
const SC_PUSH_CONSTANT: u32 = 9;
const SC_STORAGE_BUFFER: u32 = 12;

/// Whether an instruction writes through the pointer in its operand `at`: a store, a copy into it, an atomic other
/// than a load (the integer ones, the flag ones, and the float add, min and max), or an image write.
fn write_target(op: u32) -> Option<usize> {
    match op {
        OP_STORE | OP_COPY_MEMORY | OP_ATOMIC_STORE | OP_ATOMIC_FLAG_CLEAR | OP_IMAGE_WRITE => Some(0),
        229..=242 | 318 | 5614 | 5615 | 6035 => Some(2),
        _ => None,
    }
}

/// The sizes the build's checks need: of scalars, vectors, matrices, arrays of a constant length and structs.
#[derive(Default)]
struct Types {
    /// Scalar or vector type → bytes.
    plain: HashMap<u32, u32>,
    /// Matrix type → (column type, columns).
    matrices: HashMap<u32, (u32, u32)>,
    /// Array type of a constant length → the constant's id.
    lengths: HashMap<u32, u32>,
    /// Integer constants → value.
    constants: HashMap<u32, u32>,
}

/// What a module's instructions declare, gathered in one pass ([`Module::scan`]).
#[derive(Default)]
struct Scan {
    bindings: HashMap<u32, u32>,
    sets: HashMap<u32, u32>,
    spec: Vec<(u32, u32)>,
    /// Image type → (dim, sampled).
    images: HashMap<u32, (u32, u32)>,
    sampled_images: HashMap<u32, u32>,
    /// Array type → element type.
    arrays: HashMap<u32, u32>,
    /// Pointer type → (storage class, pointee).
    pointers: HashMap<u32, (u32, u32)>,
    /// (pointer type, id, storage class).
    variables: Vec<(u32, u32, u32)>,
    /// Variables decorated NonWritable.
    non_writable: HashSet<u32>,
    /// Struct → its members decorated NonWritable.
    non_writable_members: HashMap<u32, HashSet<u32>>,
    types: Types,
    /// (struct, member) → matrix stride.
    matrix_strides: HashMap<(u32, u32), u32>,
    /// Every pointer (or loaded image) derived from a global variable → the variable.
    roots: HashMap<u32, u32>,
    /// The variables the code writes through such a pointer.
    written_vars: HashSet<u32>,
}

fn string(words: &[u32]) -> String {
    let bytes: Vec<u8> = words.iter().flat_map(|w| w.to_le_bytes()).take_while(|&b| b != 0).collect();
    String::from_utf8_lossy(&bytes).into_owned()
}

impl Module {
    pub fn parse(words: &[u32]) -> Result<Module, String> {
        if words.len() < 5 || words[0] != 0x0723_0203 {
            return Err("not SPIR-V".into());
        }
        let mut m = Module::default();
        let s = m.scan(words)?;
        for &(id, spec_id) in &s.spec {
            m.spec_ids.insert(spec_id, m.names.get(&id).cloned().unwrap_or_default());
        }
        m.push_block(&s)?;
        m.descriptors(&s)?;
        Ok(m)
    }

    /// One pass over the instructions: the names, types, decorations and variables, and the writes through
    /// pointers derived from each variable.
    fn scan(&mut self, words: &[u32]) -> Result<Scan, String> {
        let mut s = Scan::default();
        let mut i = 5;
        while i < words.len() {
            let count = (words[i] >> 16) as usize;
            let op = words[i] & 0xFFFF;
            if count == 0 || i + count > words.len() {
                return Err(format!("truncated instruction at word {i}"));
            }
            let a = &words[i + 1..i + count];
            match op {
                OP_NAME => {
                    self.names.insert(a[0], string(&a[1..]));
                }
                OP_TYPE_BOOL => {
                    s.types.plain.insert(a[0], 4);
                }
                OP_TYPE_INT | OP_TYPE_FLOAT => {
                    s.types.plain.insert(a[0], a[1] / 8);
                }
                OP_TYPE_VECTOR => {
                    let bytes = s.types.plain.get(&a[1]).copied().unwrap_or(0) * a[2];
                    s.types.plain.insert(a[0], bytes);
                }
                OP_TYPE_MATRIX => {
                    s.types.matrices.insert(a[0], (a[1], a[2]));
                }
                OP_CONSTANT if a.len() == 3 => {
                    s.types.constants.insert(a[1], a[2]);
                }
                OP_TYPE_IMAGE => {
                    s.images.insert(a[0], (a[2], a[6]));
                }
                OP_TYPE_SAMPLED_IMAGE => {
                    s.sampled_images.insert(a[0], a[1]);
                }
                OP_TYPE_ARRAY | OP_TYPE_RUNTIME_ARRAY => {
                    s.arrays.insert(a[0], a[1]);
                    if op == OP_TYPE_ARRAY {
                        s.types.lengths.insert(a[0], a[2]);
                    }
                }
                OP_TYPE_STRUCT => {
                    self.struct_members.insert(a[0], a[1..].to_vec());
                }
                OP_TYPE_POINTER => {
                    s.pointers.insert(a[0], (a[1], a[2]));
                }
                OP_VARIABLE => {
                    s.variables.push((a[0], a[1], a[2]));
                    s.roots.insert(a[1], a[1]);
                }
                OP_ACCESS_CHAIN
                | OP_IN_BOUNDS_ACCESS_CHAIN
                | OP_PTR_ACCESS_CHAIN
                | OP_COPY_OBJECT
                | OP_LOAD
                | OP_IMAGE_TEXEL_POINTER => {
                    if let Some(&root) = s.roots.get(&a[2]) {
                        s.roots.insert(a[1], root);
                    }
                }
                OP_DECORATE => match a[1] {
                    DEC_SPEC_ID => s.spec.push((a[0], a[2])),
                    DEC_ARRAY_STRIDE => {
                        self.array_strides.insert(a[0], a[2]);
                    }
                    DEC_BINDING => {
                        s.bindings.insert(a[0], a[2]);
                    }
                    DEC_DESCRIPTOR_SET => {
                        s.sets.insert(a[0], a[2]);
                    }
                    DEC_NON_WRITABLE => {
                        s.non_writable.insert(a[0]);
                    }
                    _ => {}
                },
                OP_MEMBER_DECORATE if a[2] == DEC_OFFSET => {
                    self.member_offsets.entry(a[0]).or_default().insert(a[1], a[3]);
                }
                OP_MEMBER_DECORATE if a[2] == DEC_MATRIX_STRIDE => {
                    s.matrix_strides.insert((a[0], a[1]), a[3]);
                }
                OP_MEMBER_DECORATE if a[2] == DEC_NON_WRITABLE => {
                    s.non_writable_members.entry(a[0]).or_default().insert(a[1]);
                }
                _ => {}
            }
            if let Some(at) = write_target(op) {
                if let Some(root) = a.get(at).and_then(|p| s.roots.get(p)) {
                    s.written_vars.insert(*root);
                }
            }
            i += count;
        }
        Ok(s)
    }

    /// The push-constant block, if a variable holds one.
    fn push_block(&mut self, s: &Scan) -> Result<(), String> {
        for &(ptr, _, class) in &s.variables {
            if class != SC_PUSH_CONSTANT {
                continue;
            }
            let block = s.pointers.get(&ptr).map(|p| p.1).ok_or("a variable without a pointer type")?;
            let members = self.struct_members.get(&block).cloned().unwrap_or_default();
            let inner = match members[..] {
                [only] if self.struct_members.contains_key(&only) => only,
                _ => block,
            };
            let size = self.size_of(block, &s.types, &s.matrix_strides)?;
            self.push = Some(PushBlock { name: self.names.get(&inner).cloned().unwrap_or_default(), size });
        }
        Ok(())
    }

    /// Every descriptor: its kind, name, and whether the shader may write it and does.
    fn descriptors(&mut self, s: &Scan) -> Result<(), String> {
        for &(ptr, id, class) in &s.variables {
            let Some(&binding) = s.bindings.get(&id) else { continue };
            let set = s.sets.get(&id).copied().unwrap_or(0);
            let mut ty = s.pointers.get(&ptr).map(|p| p.1).ok_or("a variable without a pointer type")?;
            while let Some(&e) = s.arrays.get(&ty) {
                ty = e;
            }
            let kind = match class {
                SC_UNIFORM => Descriptor::Uniform,
                SC_STORAGE_BUFFER => Descriptor::Storage,
                SC_UNIFORM_CONSTANT => {
                    // A sampler of a buffer image (`samplerBuffer`) is a uniform texel buffer.
                    if let Some(image) = s.sampled_images.get(&ty) {
                        if s.images.get(image).is_some_and(|i| i.0 == 5) {
                            Descriptor::UniformTexel
                        } else {
                            Descriptor::Sampled
                        }
                    } else {
                        match s.images.get(&ty) {
                            // Dim Buffer: a texel buffer; sampled 1: read through a sampler, 2: a storage image.
                            Some(&(5, 1)) => Descriptor::UniformTexel,
                            Some(&(5, _)) => Descriptor::StorageTexel,
                            Some(&(_, 2)) => Descriptor::StorageImage,
                            _ => return Err(format!("binding {binding}: a descriptor of a kind not checked")),
                        }
                    }
                }
                _ => continue,
            };
            let writable = match kind {
                Descriptor::Storage => {
                    let members = self.struct_members.get(&ty).map_or(0, |v| v.len());
                    s.non_writable_members.get(&ty).map_or(0, |n| n.len()) < members
                }
                Descriptor::StorageImage | Descriptor::StorageTexel => !s.non_writable.contains(&id),
                _ => false,
            };
            if writable {
                self.writable.insert((set, binding));
                if s.written_vars.contains(&id) {
                    self.written.insert((set, binding));
                }
            }
            // A block without an instance name (`buffer SplatBuf { ... };`) is named by its block.
            let name = self.names.get(&id).filter(|n| !n.is_empty()).or_else(|| self.names.get(&ty)).cloned();
            self.bindings.insert((set, binding), (kind, name.unwrap_or_default()));
        }
        Ok(())
    }

    /// The bytes a value of type `ty` takes in an explicitly laid out block (a struct: its last member's offset
    /// plus that member's size).
    fn size_of(&self, ty: u32, types: &Types, strides: &HashMap<(u32, u32), u32>) -> Result<u32, String> {
        if let Some(&bytes) = types.plain.get(&ty) {
            return Ok(bytes);
        }
        if let Some(&len) = types.lengths.get(&ty) {
            let stride = *self.array_strides.get(&ty).ok_or("an array without a stride")?;
            return Ok(stride * types.constants.get(&len).copied().ok_or("an array of a length not constant")?);
        }
        if let Some(members) = self.struct_members.get(&ty) {
            let mut end = 0;
            for (k, &member) in members.iter().enumerate() {
                let offset = self.member_offsets.get(&ty).and_then(|o| o.get(&(k as u32))).copied().unwrap_or(0);
                let bytes = match types.matrices.get(&member) {
                    Some(&(_, columns)) => {
                        strides.get(&(ty, k as u32)).copied().ok_or("a matrix without a stride")? * columns
                    }
                    None => self.size_of(member, types, strides)?,
                };
                end = end.max(offset + bytes);
            }
            return Ok(end);
        }
        Err(format!("type {ty}: a size not read"))
    }
}
