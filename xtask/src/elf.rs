//! Just enough of ELF32 (little-endian, as the Cortex-M images are) to size an image: the
//! section headers with their names, types, flags and sizes.

/// One section.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Section {
    pub name: String,
    pub kind: u32,
    pub flags: u32,
    pub addr: u32,
    pub size: u32,
}

const SHT_NOBITS: u32 = 8;
const SHF_WRITE: u32 = 0x1;
const SHF_ALLOC: u32 = 0x2;

impl Section {
    /// Loaded into the target's memory.
    pub fn alloc(&self) -> bool {
        self.flags & SHF_ALLOC != 0
    }

    /// Has bytes in the image (not `.bss`-like).
    pub fn has_bits(&self) -> bool {
        self.kind != SHT_NOBITS
    }

    /// Writable at run time (lives in RAM).
    pub fn writable(&self) -> bool {
        self.flags & SHF_WRITE != 0
    }
}

/// Flash and static RAM an image needs, bytes.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Sizes {
    /// Everything stored in flash: code, read-only data, vector table, `.data`'s initial values.
    pub flash: u64,
    /// Everything statically placed in RAM: `.data`, `.bss`, `.uninit` (not the stack).
    pub ram: u64,
}

/// Flash and static RAM of the sections.
pub fn sizes(sections: &[Section]) -> Sizes {
    let mut sizes = Sizes { flash: 0, ram: 0 };
    for s in sections.iter().filter(|s| s.alloc()) {
        if s.has_bits() {
            sizes.flash += u64::from(s.size);
        }
        if s.writable() {
            sizes.ram += u64::from(s.size);
        }
    }
    sizes
}

/// The section headers of an ELF32 little-endian file.
pub fn sections(bytes: &[u8]) -> Result<Vec<Section>, String> {
    if bytes.get(..4) != Some(b"\x7fELF".as_slice()) {
        return Err("not an ELF file".into());
    }
    if bytes.get(4) != Some(&1) || bytes.get(5) != Some(&1) {
        return Err("not a 32-bit little-endian ELF file".into());
    }
    let shoff = u32_at(bytes, 0x20)? as usize;
    let shentsize = usize::from(u16_at(bytes, 0x2E)?);
    let shnum = usize::from(u16_at(bytes, 0x30)?);
    let shstrndx = usize::from(u16_at(bytes, 0x32)?);
    let header = |i: usize| -> Result<[u32; 6], String> {
        let base = shoff + i * shentsize;
        Ok([
            u32_at(bytes, base)?,      // name offset
            u32_at(bytes, base + 4)?,  // type
            u32_at(bytes, base + 8)?,  // flags
            u32_at(bytes, base + 12)?, // address
            u32_at(bytes, base + 16)?, // file offset
            u32_at(bytes, base + 20)?, // size
        ])
    };
    let names = header(shstrndx)?;
    let (names_off, names_size) = (names[4] as usize, names[5] as usize);
    let names = bytes
        .get(names_off..names_off + names_size)
        .ok_or("section names out of the file")?;
    (0..shnum)
        .map(|i| {
            let [name, kind, flags, addr, _, size] = header(i)?;
            let name = names
                .get(name as usize..)
                .and_then(|rest| rest.split(|&b| b == 0).next())
                .map(|n| String::from_utf8_lossy(n).into_owned())
                .unwrap_or_default();
            Ok(Section {
                name,
                kind,
                flags,
                addr,
                size,
            })
        })
        .collect()
}

fn u32_at(bytes: &[u8], at: usize) -> Result<u32, String> {
    bytes
        .get(at..at + 4)
        .and_then(|b| b.try_into().ok())
        .map(u32::from_le_bytes)
        .ok_or_else(|| format!("ELF file truncated at {at:#x}"))
}

fn u16_at(bytes: &[u8], at: usize) -> Result<u16, String> {
    bytes
        .get(at..at + 2)
        .and_then(|b| b.try_into().ok())
        .map(u16::from_le_bytes)
        .ok_or_else(|| format!("ELF file truncated at {at:#x}"))
}
